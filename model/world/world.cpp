#include "model/world/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "model/beam/rotation.hpp"
#include "model/model_error.hpp"

namespace scopekin::model {
namespace {

Eigen::Matrix3d roll_about_x(double angle_rad) {
    return Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

/// Roll of a node about the entry axis (+x in the computation frame) [rad, (-pi, pi]].
double roll_of(const Eigen::Matrix3d& r) {
    return std::atan2(r(2, 1), r(1, 1));
}

double wrap_pi(double a) {
    return std::remainder(a, 2.0 * M_PI);
}

ColonTube transformed_tube(const ColonTube& tube, const Eigen::Matrix3d& rotation,
                           const Eigen::Vector3d& origin, double scope_radius_mm) {
    std::vector<ColonPoint> points = tube.points();
    for (ColonPoint& p : points)
        p.position_mm = rotation * (p.position_mm - origin);
    return ColonTube(tube.name(), std::move(points), scope_radius_mm);
}

}  // namespace

void WorldContactSettings::validate() const {
    require_non_negative(activation_distance_mm, "contact.activation_distance_mm");
    require_non_negative(wall_compliance_mm_per_N, "contact.wall_compliance_mm_per_N");
    require_non_negative(friction_coefficient, "contact.friction_coefficient");
    require_positive(tolerance_N, "contact.tolerance_N");
    if (max_sweeps < 1) throw ModelError("contact.max_sweeps: must be >= 1");
    if (!(relaxation > 0.0 && relaxation < 2.0))
        throw ModelError("contact.relaxation: must be in (0, 2)");
    for (std::size_t i = 0; i < friction_zones.size(); ++i) {
        const std::string where = "contact.friction_zones[" + std::to_string(i) + "]";
        const FrictionZone& z = friction_zones[i];
        require_non_negative(z.from_tip_mm, where + ".from_tip_mm");
        require_non_negative(z.coefficient, where + ".coefficient");
        require_finite(z.to_tip_mm, where + ".to_tip_mm");
        if (!(z.to_tip_mm > z.from_tip_mm))
            throw ModelError(where + ": to_tip_mm must be greater than from_tip_mm");
    }
}

void WorldSettings::validate() const {
    validate_time_step_and_damping(time_step_s, damping, "solver");
    if (newton_iterations < 1 || newton_iterations > 50)
        throw ModelError("solver.newton_iterations: must be in [1, 50]");
    if (!gravity_mm_per_s2.allFinite()) throw ModelError("gravity_mm_per_s2: not finite");
    require_non_negative(initial_insertion_mm, "initial_insertion_mm");
    contact.validate();
    telescoping.validate();
}

World::World(const ScopeSpec& scope, const ColonTube& colon,
             const std::array<ColonRegionProperties, 8>& properties, WorldSettings settings,
             std::vector<std::shared_ptr<const WorldEffect>> effects)
    : settings_(std::move(settings)),
      relaxation_(settings_.contact.relaxation),
      effects_(std::move(effects)),
      body_tube_(colon),
      tube_(colon),
      scope_(
          straight_beam(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), 1.0, 1, scope.section)) {
    settings_.validate();
    require_positive(scope.length_mm, "scope.length_mm");
    require_positive(scope.radius_mm, "scope.radius_mm");
    if (scope.elements < 2 || scope.elements > 2000)
        throw ModelError("scope.elements: must be in [2, 2000]");
    if (settings_.initial_insertion_mm >= scope.length_mm)
        throw ModelError("initial_insertion_mm: must be shorter than the scope (" +
                         std::to_string(scope.length_mm) + " mm)");
    length_mm_ = scope.length_mm;
    scope_radius_mm_ = scope.radius_mm;

    // Computation frame: anus at the origin, the colon's first segment along +x.
    anus_ = colon.points()[0].position_mm;
    const Eigen::Vector3d entry = (colon.points()[1].position_mm - anus_).normalized();
    rotation_ =
        Eigen::Quaterniond::FromTwoVectors(entry, Eigen::Vector3d::UnitX()).toRotationMatrix();
    gravity_ = rotation_ * settings_.gravity_mm_per_s2;
    tube_ = transformed_tube(colon, rotation_, anus_, scope.radius_mm);
    for (const ColonPoint& p : tube_.points())
        colon_rest_mm_.push_back(p.position_mm);

    std::array<ColonRegionProperties, 8> colon_properties = properties;
    for (const auto& e : effects_)
        e->adjust_colon_properties(colon_properties);
    const ColonStructure structure = build_colon_structure(tube_, colon_properties);
    compliance_ = std::make_unique<ColonCompliance>(structure);
    pleating_ =
        std::make_unique<ColonPleating>(colon_rest_mm_, structure.mobile, settings_.telescoping);
    pleated_tube_mm_ = colon_rest_mm_;
    colon_rest_at_start_mm_ = colon_rest_mm_;

    std::vector<BeamSection> sections(scope.elements, scope.section);
    for (const auto& e : effects_)
        e->adjust_scope_sections(sections, scope.length_mm);
    if (sections.size() != scope.elements)
        throw ModelError("a truth effect changed the number of scope sections");
    std::vector<Eigen::Vector3d> nodes;
    const double start = settings_.initial_insertion_mm - scope.length_mm;
    for (std::size_t i = 0; i <= scope.elements; ++i)
        nodes.emplace_back(
            start + scope.length_mm * static_cast<double>(i) / static_cast<double>(scope.elements),
            0.0, 0.0);
    scope_ = ScopeBeam(std::move(nodes), std::move(sections));
    velocity_ = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(scope_.dof_count()));
    warm_start_.assign(scope_.node_count(), {0.0, 0.0, 0.0});
    wall_deflection_mm_.assign(scope_.node_count(), Eigen::Vector3d::Zero());
    contact_force_N_.assign(scope_.node_count(), Eigen::Vector3d::Zero());
    problem_ = std::make_unique<Problem>();
    forces_ = std::make_unique<Forces>();

    // The inserted part starts straight on the entry axis: it must fit in the lumen.
    const auto initial =
        detect_contacts(scope_, colon_rest_mm_, tube_, {scope.radius_mm, 0.0}, {}, nullptr);
    for (const ContactCandidate& c : initial)
        if (c.gap_mm < -1e-9) {
            std::ostringstream m;
            m << "initial_insertion_mm: " << settings_.initial_insertion_mm
              << " mm of straight scope would cross the colon wall (" << -c.gap_mm << " mm deep at "
              << arc_from_tip_mm(c.scope_node)
              << " mm from the tip); the colon's entry is not straight that far";
            throw ModelError(m.str());
        }
}

double World::insertion_depth_mm() const {
    return scope_.position(0).x() + length_mm_;
}

Eigen::Vector3d World::node_position_mm(std::size_t node) const {
    return to_body(scope_.position(node));
}

Eigen::Vector3d World::node_velocity_mm_per_s(std::size_t node) const {
    return to_body_direction(velocity_.segment<3>(static_cast<Eigen::Index>(6 * node)));
}

Eigen::Vector3d World::node_axis(std::size_t node) const {
    const std::size_t e = std::min(node, scope_.element_count() - 1);
    return to_body_direction((scope_.position(e + 1) - scope_.position(e)).normalized());
}

std::vector<Eigen::Vector3d> World::colon_positions_mm() const {
    std::vector<Eigen::Vector3d> u;
    compliance_->displacement(colon_forces_, u);
    std::vector<Eigen::Vector3d> out(u.size());
    for (std::size_t i = 0; i < u.size(); ++i)
        out[i] = to_body(colon_rest_mm_[i] + u[i]);
    return out;
}

World::State World::state() const {
    State s;
    s.time_s = time_s_;
    s.steps_taken = steps_taken_;
    s.roll_rad = roll_rad_;
    s.handle_force_N = handle_force_N_;
    s.handle_torque_Nmm = handle_torque_Nmm_;
    s.scope = scope_.configuration();
    s.velocity = velocity_;
    s.colon_forces = colon_forces_;
    s.previous_colon_forces = previous_colon_forces_;
    s.contacts = contact_reports_;
    s.warm_start = warm_start_;
    s.wall_deflection_mm = wall_deflection_mm_;
    s.contact_force_N = contact_force_N_;
    s.tracking = tracking_;
    s.telescoping = pleating_->state();
    s.pleated_tube_mm = pleated_tube_mm_;
    return s;
}

void World::restore(const State& saved) {
    if (saved.scope.positions.size() != scope_.node_count() ||
        saved.warm_start.size() != scope_.node_count() ||
        saved.wall_deflection_mm.size() != scope_.node_count() ||
        saved.contact_force_N.size() != scope_.node_count() ||
        saved.velocity.size() != static_cast<Eigen::Index>(scope_.dof_count()))
        throw ModelError("restore: the saved state is of a scope with " +
                         std::to_string(saved.scope.positions.size()) +
                         " nodes, this world's has " + std::to_string(scope_.node_count()));
    const auto colon_nodes = static_cast<std::size_t>(colon_rest_mm_.size());
    for (const auto* forces : {&saved.colon_forces, &saved.previous_colon_forces})
        for (const ColonPointForce& f : *forces)
            if (f.segment + 1 >= colon_nodes)
                throw ModelError("restore: the saved state is of another colon");
    const double h = settings_.time_step_s;
    if (std::abs(static_cast<double>(saved.steps_taken) * h - saved.time_s) >
        1e-9 * std::max(1.0, saved.time_s))
        throw ModelError("restore: the saved state was taken with another time step");
    time_s_ = saved.time_s;
    steps_taken_ = saved.steps_taken;
    roll_rad_ = saved.roll_rad;
    handle_force_N_ = saved.handle_force_N;
    handle_torque_Nmm_ = saved.handle_torque_Nmm;
    scope_.restore(saved.scope);
    velocity_ = saved.velocity;
    colon_forces_ = saved.colon_forces;
    previous_colon_forces_ = saved.previous_colon_forces;
    contact_reports_ = saved.contacts;
    warm_start_ = saved.warm_start;
    wall_deflection_mm_ = saved.wall_deflection_mm;
    contact_force_N_ = saved.contact_force_N;
    tracking_ = saved.tracking;
    pleating_->restore(saved.telescoping);
    colon_rest_mm_ = saved.telescoping.position_mm;
    if (saved.pleated_tube_mm.size() != colon_rest_mm_.size())
        throw ModelError("restore: the saved state is of another colon (pleated tube)");
    pleated_tube_mm_ = saved.pleated_tube_mm;
    pleated_body_tube_.reset();
    if (pleated_tube_mm_ != colon_rest_at_start_mm_) refresh_pleated_tube(true);
}

void World::refresh_pleated_tube(bool always) {
    // The effects that press the colon back to its place (abdominal pressure) see it pleated. The
    // tube is rebuilt (its checks are O(points^2)) only once a node has moved kTubeRefresh_mm
    // since the last one, and never without effects; the positions it was built from are part of
    // the state, so a restored run continues bit for bit.
    if (effects_.empty()) return;
    const std::vector<Eigen::Vector3d>& from = always ? pleated_tube_mm_ : colon_rest_mm_;
    if (!always) {
        double moved_mm = 0.0;
        for (std::size_t i = 0; i < colon_rest_mm_.size(); ++i)
            moved_mm = std::max(moved_mm, (colon_rest_mm_[i] - pleated_tube_mm_[i]).norm());
        if (moved_mm < kTubeRefresh_mm) return;
    }
    std::vector<ColonPoint> points = body_tube_.points();
    for (std::size_t i = 0; i < points.size() && i < from.size(); ++i)
        points[i].position_mm = to_body(from[i]);
    try {
        pleated_body_tube_ =
            std::make_unique<ColonTube>(body_tube_.name(), std::move(points), scope_radius_mm_);
        pleated_tube_mm_ = from;
    } catch (const ModelError&) {
        // A pleated shape the tube's checks refuse: the effects keep the last one that passed.
    }
}

Eigen::Vector3d World::colon_position_mm(std::size_t node) const {
    if (node >= colon_rest_mm_.size())
        throw ModelError("colon_position_mm: no colon node " + std::to_string(node));
    return to_body(colon_rest_mm_[node] + compliance_->node_displacement(node, colon_forces_));
}

double World::scope_energy_Nmm() const {
    BlockTridiagonalMatrix mass;
    scope_.assemble_mass(mass);
    const Eigen::VectorXd f_gravity = scope_.gravity_load(gravity_);
    double potential = 0.0;
    for (std::size_t i = 0; i < scope_.node_count(); ++i)
        potential -= f_gravity.segment<3>(static_cast<Eigen::Index>(6 * i)).dot(scope_.position(i));
    return 0.5 * velocity_.dot(mass.multiply(velocity_)) + scope_.strain_energy_Nmm() + potential;
}

double World::friction_at(double arc_from_tip, ColonRegion region,
                          double sliding_speed_mm_per_s) const {
    double mu = settings_.contact.friction_coefficient;
    for (const FrictionZone& z : settings_.contact.friction_zones)
        if (arc_from_tip >= z.from_tip_mm && arc_from_tip < z.to_tip_mm) mu = z.coefficient;
    for (const auto& e : effects_)
        mu = e->friction_coefficient(
            ContactFrictionView{arc_from_tip, region, mu, sliding_speed_mm_per_s});
    return std::max(0.0, mu);
}

namespace {
/// Largest displacement of a scope node in one step that World::attempt accepts [mm].
constexpr double kMaxNodeStep_mm = 10.0;

// Penetration a contact began its step with is removed at most at this speed; what the step's own
// free motion adds is removed in full. The contact problem asks for a closed gap at the step's
// end, so a node found deep in the wall at the start (a contact released the step before, with
// the massless colon springing back to rest under it) was thrown out at depth / h, 1-2 m/s, across
// the lumen: the next step found it on the other side of the colon point it touched, its normal
// flipped, the contact released, the colon sprang back — a period-2 cycle of the contact forces
// in 30-43 % of the steps of some careful experts' runs and a median 33 % of the hurried
// trainees' (model/truth/README.md). Limiting the depenetration speed is the usual cure in
// time-stepping contact (e.g. the split impulse or "maximum depenetration velocity" of game
// physics engines; Catto, "Iterative Dynamics with Temporal Coherence", GDC 2005, on Baumgarte
// stabilisation). 100 mm/s is above the hands' 8-40 mm/s advance and a wall spring's recoil, so
// a node pushed into the wall within a step still stops at it.
constexpr double kMaxDepenetration_mm_per_s = 100.0;

/// The penetration a contact may keep at the step's end [mm, >= 0]: what it began the step with
/// beyond kMaxDepenetration_mm_per_s x h. The start gap is the free gap moved back to the step's
/// start position (`back_to_start_mm`), against the colon where the last forces held it
/// (`colon_held_mm`: g_held = g_rest - n . u) with the wall's spring compressed by the last normal
/// force (`wall_spring_mm`): the gap the last contact solve closed.
double penetration_allowed_mm(const ContactCandidate& c, const Eigen::Vector3d& back_to_start_mm,
                              const Eigen::Vector3d& colon_held_mm, double wall_spring_mm,
                              double h) {
    const Eigen::Vector3d n = c.frame.col(0);
    const double start_gap_mm =
        c.gap_mm + n.dot(back_to_start_mm) - n.dot(colon_held_mm) + wall_spring_mm;
    return std::max(0.0, -(start_gap_mm + kMaxDepenetration_mm_per_s * h));
}

/// One pair's block of the contact problem's Delassus operator in the contacts' frames [mm/N]
/// (thesis Eq. 4.24): the scope's part, which also carries the last step's forces into the free
/// motion, and the sum with the colon's. The scope's block comes in as a Matrix3d: multiplied as
/// a block expression of the dynamic matrix it cost more in building the expression than in the
/// arithmetic (a validation case 6 % slower, the same numbers).
struct DelassusPair {
    Eigen::Matrix3d scope;
    Eigen::Matrix3d total;
};
DelassusPair delassus_pair(const Eigen::Matrix3d& frame_a, const Eigen::Matrix3d& scope_block,
                           const Eigen::Matrix3d& colon_block, const Eigen::Matrix3d& frame_b) {
    DelassusPair p;
    p.scope = frame_a.transpose() * scope_block * frame_b;
    p.total = p.scope + frame_a.transpose() * colon_block * frame_b;
    return p;
}

/// How often a step may be halved before the material tangent is used instead (see World::step).
constexpr int kMaxStepHalvings = 1;

/// The report of two consecutive half steps as one step's.
WorldStepReport combined(const WorldStepReport& first, const WorldStepReport& second) {
    WorldStepReport r = second;
    r.dropped_contacts = std::max(first.dropped_contacts, second.dropped_contacts);
    r.sweeps = first.sweeps + second.sweeps;
    r.contact_residual_N = std::max(first.contact_residual_N, second.contact_residual_N);
    r.max_penetration_mm = std::max(first.max_penetration_mm, second.max_penetration_mm);
    r.friction_work_Nmm = first.friction_work_Nmm + second.friction_work_Nmm;
    r.substeps = first.substeps + second.substeps;
    return r;
}
}  // namespace

WorldStepReport World::step(const HandleCommand& command) {
    // A scope pushed hard against a wall is compressed beyond buckling between its contacts: the
    // full tangent (material + geometric) can then make the step matrix indefinite and the contact
    // problem ill-posed. Stiffness-proportional damping (b K / h) keeps it definite at smaller
    // steps, so the step is first halved; only if that fails too is the material tangent alone
    // used, which stays positive definite (the exact internal force in the residual still drives
    // the state to equilibrium, but a slow contact state drifts: with it, a tip self-locked at
    // 10 ms steps slipped where it held at 5 and 2 ms).
    const double h = settings_.time_step_s;
    const State before = state();
    WorldStepReport report = advance_with_full_tangent(command, h, time_s_, 0);
    if (!report.ok) {
        WorldStepReport retry = attempt(command, false, h, time_s_);
        if (retry.ok) {
            retry.material_tangent_fallback = true;
            report = retry;
        } else {
            restore(before);
            WorldStepReport relaxed = attempt_under_relaxed(command);
            if (!relaxed.ok) {
                restore(before);
                return report;
            }
            report = relaxed;
        }
    }
    ++steps_taken_;
    time_s_ = static_cast<double>(steps_taken_) * h;  // no drift from summing h
    // Telescoping, staggered: the drag of this step's contact forces pleats the mobile stretches;
    // the next step's contacts meet the colon in its new rest shape.
    if (pleating_->advance(colon_forces_, h)) {
        colon_rest_mm_ = pleating_->state().position_mm;
        refresh_pleated_tube(false);
    }
    return report;
}

WorldStepReport World::advance_with_full_tangent(const HandleCommand& command, double h,
                                                 double t_start_s, int halvings) {
    const State before = state();
    WorldStepReport report = attempt(command, true, h, t_start_s);
    if (report.ok) return report;
    restore(before);
    if (halvings >= kMaxStepHalvings) return report;
    const WorldStepReport first =
        advance_with_full_tangent(halfway_command(command), 0.5 * h, t_start_s, halvings + 1);
    if (first.ok) {
        const WorldStepReport second =
            advance_with_full_tangent(command, 0.5 * h, t_start_s + 0.5 * h, halvings + 1);
        if (second.ok) return combined(first, second);
    }
    restore(before);
    return report;
}

namespace {
/// Gauss-Seidel's omega for a step whose contact solve cycled at the scenario's (see below).
constexpr double kCyclingRelaxation = 0.7;
}  // namespace

WorldStepReport World::attempt_under_relaxed(const HandleCommand& command) {
    // Projected Gauss-Seidel on a frictional contact problem can cycle instead of converging
    // (many contacts switching between stick and slip; the change per sweep stays at 0.01-0.1 N
    // after 20,000 sweeps). Under-relaxation damps the cycle (measured: a drawn patient's step with
    // 36 contacts cycled at omega = 1 and converged at 0.7 and 0.9). Only a step that failed
    // every other way comes here, so a run that needs no rescue is unchanged.
    const State before = state();
    relaxation_ = kCyclingRelaxation;
    WorldStepReport report = attempt(command, true, settings_.time_step_s, time_s_);
    if (!report.ok) {
        restore(before);
        report = attempt(command, false, settings_.time_step_s, time_s_);
        report.material_tangent_fallback = report.ok;
    }
    relaxation_ = settings_.contact.relaxation;
    report.under_relaxed = report.ok;
    return report;
}

HandleCommand World::halfway_command(const HandleCommand& command) const {
    HandleCommand half = command;
    half.insertion_mm = 0.5 * (insertion_depth_mm() + command.insertion_mm);
    half.roll_rad = roll_rad_ + 0.5 * wrap_pi(command.roll_rad - roll_rad_);
    return half;
}

WorldStepReport World::attempt(const HandleCommand& command, bool geometric_tangent, double h,
                               double t_start_s) {
    WorldStepReport report;
    const std::size_t nodes = scope_.node_count();
    const auto dofs = static_cast<Eigen::Index>(scope_.dof_count());
    if (!std::isfinite(command.insertion_mm) || !std::isfinite(command.push_force_N) ||
        !std::isfinite(command.roll_rad) || !std::isfinite(command.torque_Nmm)) {
        report.failure = "handle command is not finite";
        return report;
    }
    const ScopeBeam::Configuration start = scope_.configuration();

    // 1. The nodes the hand holds on the entry axis (always the handle node itself).
    std::vector<bool> held(nodes, false);
    held[0] = true;
    for (std::size_t k = 1; k < nodes; ++k) {
        const double x = command.force_controlled ? scope_.position(k).x()
                                                  : command.insertion_mm - arc_from_tip_mm(k);
        held[k] = x <= 1e-9;
    }
    std::vector<std::size_t> held_dofs;
    std::vector<double> held_increments;
    auto hold = [&](std::size_t dof, double increment) {
        held_dofs.push_back(dof);
        held_increments.push_back(increment);
    };
    for (std::size_t k = 0; k < nodes; ++k) {
        if (!held[k]) continue;
        const Eigen::Vector3d& x = scope_.position(k);
        if (!command.force_controlled)
            hold(6 * k, command.insertion_mm - arc_from_tip_mm(k) - x.x());
        hold(6 * k + 1, -x.y());
        hold(6 * k + 2, -x.z());
        const Eigen::Matrix3d& r = scope_.rotation(k);
        const double roll_target = command.torque_controlled ? roll_of(r) : command.roll_rad;
        const Eigen::Vector3d spin = rotation_log(roll_about_x(roll_target) * r.transpose());
        if (!command.torque_controlled) hold(6 * k + 3, spin.x());
        hold(6 * k + 4, spin.y());
        hold(6 * k + 5, spin.z());
    }

    // 2. Loads at the end of the step: gravity, the handle's force/torque, truth effects (those
    //    that follow the node's position with a stiffness are implicit in the step: 3. below).
    struct LoadStiffness {
        std::size_t node;
        Eigen::Matrix3d stiffness_N_per_mm;  // world frame
    };
    std::vector<LoadStiffness> load_stiffness;
    std::vector<NodalLoad> loads;           // body frame, as the effects gave them
    std::vector<std::size_t> loads_end_of;  // per effect: loads.size() after its turn
    // The shaft outside the body is carried by the hand and the box: gravity acts inside only.
    Eigen::VectorXd f_ext = scope_.gravity_load(gravity_);
    for (std::size_t k = 0; k < nodes; ++k)
        if (held[k]) f_ext.segment<3>(static_cast<Eigen::Index>(6 * k)).setZero();
    if (command.force_controlled) f_ext(0) += command.push_force_N;
    if (command.torque_controlled) f_ext(3) += command.torque_Nmm;
    if (!effects_.empty()) {
        WorldEffectView view;
        view.time_s = t_start_s + h;
        view.time_step_s = h;
        view.insertion_depth_mm = insertion_depth_mm();
        view.scope_radius_mm = scope_radius_mm_;
        view.colon_at_rest = pleated_body_tube_ ? pleated_body_tube_.get() : &body_tube_;
        view.scope_node_held = held;
        for (std::size_t k = 0; k < nodes; ++k) {
            view.scope_nodes_mm.push_back(node_position_mm(k));
            view.arc_from_tip_mm.push_back(arc_from_tip_mm(k));
            view.scope_velocities_mm_per_s.push_back(node_velocity_mm_per_s(k));
            view.scope_axes.push_back(node_axis(k));
        }
        for (const auto& e : effects_) {
            e->add_scope_loads(view, loads);
            loads_end_of.push_back(loads.size());
        }
        for (const NodalLoad& l : loads) {
            if (l.node >= nodes || !l.force_N.allFinite() || !l.moment_Nmm.allFinite() ||
                !l.stiffness_N_per_mm.allFinite()) {
                report.failure = "a truth effect produced an invalid load";
                return report;
            }
            f_ext.segment<3>(static_cast<Eigen::Index>(6 * l.node)) += rotation_ * l.force_N;
            f_ext.segment<3>(static_cast<Eigen::Index>(6 * l.node + 3)) += rotation_ * l.moment_Nmm;
            if (!l.stiffness_N_per_mm.isZero(0.0) && !held[l.node])
                load_stiffness.push_back(
                    {l.node, rotation_ * l.stiffness_N_per_mm * rotation_.transpose()});
        }
        std::vector<Eigen::Vector3d> curvature(nodes - 1, Eigen::Vector3d::Zero());
        for (const auto& e : effects_)
            e->add_rest_curvature(view, curvature);
        for (std::size_t k = 0; k + 1 < nodes; ++k) {
            if (curvature.size() + 1 != nodes || !curvature[k].allFinite()) {
                report.failure = "a truth effect produced an invalid rest curvature";
                return report;
            }
            scope_.set_rest_curvature(k, rotation_ * curvature[k]);
        }
    }

    // Under full position control the hand moves the outside shaft rigidly: the elements between
    // held nodes carry no strain, and their inertia is the hand's business, not the colon's. They
    // are left out, so the cost follows the inserted length. The last held node (at the anus) keeps
    // its element into the body, whose force is the handle force.
    std::size_t first_element = 0;
    if (!command.force_controlled && !command.torque_controlled)
        while (first_element + 1 < nodes && held[first_element + 1])
            ++first_element;

    // 3. Free motion: Newton on (M/h^2 + C/h + K_T) d = r, M and C frozen at the step's start,
    //    under the last step's contact forces: the contact problem then solves for their change
    //    (small from one step to the next) and its linearisation about the free configuration
    //    holds. Free of the contact forces, a scope pressed into a bend would spring straight
    //    by millimetres at large steps, and the handle force would depend on the step size.
    for (std::size_t k = 0; k < nodes; ++k)
        if (!held[k]) f_ext.segment<3>(static_cast<Eigen::Index>(6 * k)) += contact_force_N_[k];
    Eigen::VectorXd increment_total = Eigen::VectorXd::Zero(dofs);
    Eigen::VectorXd last_residual, last_increment;
    Eigen::VectorXd momentum;
    for (int it = 0; it < settings_.newton_iterations; ++it) {
        scope_.assemble(assembly_, true, it == 0 ? &mass_ : nullptr, first_element);
        const double a_damp = settings_.damping.mass_coefficient_per_s,
                     b_damp = settings_.damping.stiffness_coefficient_s;
        unconstrained_ = geometric_tangent ? assembly_.tangent : assembly_.material_tangent;
        Eigen::VectorXd residual = f_ext - assembly_.internal_force;
        // Position-following loads at the step's end: F - K d (their K in the step matrix).
        for (const LoadStiffness& l : load_stiffness) {
            const auto at = static_cast<Eigen::Index>(6 * l.node);
            unconstrained_.diagonal(l.node).topLeftCorner<3, 3>() += l.stiffness_N_per_mm;
            residual.segment<3>(at) -= l.stiffness_N_per_mm * increment_total.segment<3>(at);
        }
        if (it == 0) {
            // C = a' M + b' K_material, frozen at the step's start; d = 0 so far.
            momentum = mass_.multiply(velocity_) / h;
            unconstrained_.add_scaled(mass_, 1.0 / (h * h) + a_damp / h);
            unconstrained_.add_scaled(assembly_.material_tangent, b_damp / h);
            if (settings_.newton_iterations > 1) {
                damping_ = mass_;
                damping_.set_zero();
                damping_.add_scaled(mass_, a_damp);
                damping_.add_scaled(assembly_.material_tangent, b_damp);
            }
            residual += momentum;
        } else {
            unconstrained_.add_scaled(mass_, 1.0 / (h * h));
            unconstrained_.add_scaled(damping_, 1.0 / h);
            residual += momentum - mass_.multiply(increment_total) / (h * h) -
                        damping_.multiply(increment_total) / h;
        }
        Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(dofs);
        if (it == 0)
            for (std::size_t c = 0; c < held_dofs.size(); ++c)
                prescribed(static_cast<Eigen::Index>(held_dofs[c])) = held_increments[c];
        Eigen::VectorXd rhs = residual - unconstrained_.multiply(prescribed);
        system_ = unconstrained_;
        for (std::size_t dof : held_dofs) {
            rhs(static_cast<Eigen::Index>(dof)) = prescribed(static_cast<Eigen::Index>(dof));
            system_.constrain_dof(dof);
        }
        if (!rhs.allFinite() || !factorization_.factorize(system_)) {
            report.failure = "free motion: the scope's step matrix is singular or not finite";
            return report;
        }
        const Eigen::VectorXd increment = factorization_.solve(rhs);
        if (!increment.allFinite()) {
            report.failure = "free motion: the step increment is not finite";
            return report;
        }
        scope_.apply_increment(increment);
        increment_total += increment;
        last_residual = std::move(residual);
        last_increment = increment;
    }

    // 4. Contacts at the free configuration, against the colon at rest (it is massless and
    //    elastic: without contact forces it returns there).
    //    A node that carried a contact force stays a candidate whatever its gap: that force
    //    pushed it off the wall in the free motion, and releasing it unchecked would let it
    //    spring through the wall.
    std::vector<ContactCandidate> candidates =
        detect_contacts(scope_, colon_rest_mm_, tube_,
                        {scope_radius_mm_, std::numeric_limits<double>::max()}, held, &tracking_);
    candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                    [&](const ContactCandidate& c) {
                                        return c.gap_mm >
                                                   settings_.contact.activation_distance_mm &&
                                               contact_force_N_[c.scope_node].isZero(0.0);
                                    }),
                     candidates.end());
    if (candidates.size() > kMaxWorldContacts) {
        std::sort(candidates.begin(), candidates.end(),
                  [](const ContactCandidate& a, const ContactCandidate& b) {
                      return a.gap_mm < b.gap_mm;
                  });
        report.dropped_contacts = candidates.size() - kMaxWorldContacts;
        candidates.resize(kMaxWorldContacts);
        std::sort(candidates.begin(), candidates.end(),
                  [](const ContactCandidate& a, const ContactCandidate& b) {
                      return a.scope_node < b.scope_node;
                  });
    }
    const std::size_t nc = candidates.size();
    Problem& problem = *problem_;
    Forces& forces = *forces_;
    problem.contact_count = nc;
    std::vector<double> mu(nc, 0.0);
    Eigen::VectorXd correction = Eigen::VectorXd::Zero(dofs);
    // The free motion carried last step's contact forces; where a contact is gone, its force is
    // released now (its nodes spring free before the contacts that remain are solved).
    std::vector<bool> in_contact(nodes, false);
    for (const ContactCandidate& c : candidates)
        in_contact[c.scope_node] = true;
    Eigen::VectorXd released = Eigen::VectorXd::Zero(dofs);
    bool any_released = false;
    for (std::size_t k = 0; k < nodes; ++k)
        if (!in_contact[k] && !held[k] && !contact_force_N_[k].isZero(0.0)) {
            released.segment<3>(static_cast<Eigen::Index>(6 * k)) = -contact_force_N_[k];
            any_released = true;
        }
    if (any_released) {
        const Eigen::VectorXd release_increment = factorization_.solve(released);
        if (!release_increment.allFinite()) {
            report.failure = "contact: the release of lost contacts is not finite";
            return report;
        }
        scope_.apply_increment(release_increment);
        increment_total += release_increment;
        last_increment += release_increment;
        for (ContactCandidate& c : candidates)
            c.gap_mm += c.frame.col(0).dot(
                release_increment.segment<3>(static_cast<Eigen::Index>(6 * c.scope_node)));
    }
    // Last step's force at each contact, in its frame now (zero for a new contact).
    std::vector<Eigen::Vector3d> carried(nc);
    for (std::size_t a = 0; a < nc; ++a)
        carried[a] = candidates[a].frame.transpose() * contact_force_N_[candidates[a].scope_node];
    if (nc > 0) {
        std::vector<std::size_t> contact_nodes(nc);
        for (std::size_t a = 0; a < nc; ++a)
            contact_nodes[a] = candidates[a].scope_node;
        Eigen::MatrixXd scope_blocks;
        if (!selected_inverse_.translational_blocks(system_, contact_nodes, scope_blocks)) {
            report.failure =
                "contact: the scope's Delassus operator could not be formed (singular step matrix)";
            return report;
        }
        // The wall's local compliance per contact (truth effects may make it depend on the force).
        std::vector<double> wall_compliance(nc, settings_.contact.wall_compliance_mm_per_N);
        std::vector<double> penetration_kept_mm(nc, 0.0);
        if (!effects_.empty())
            for (std::size_t a = 0; a < nc; ++a) {
                const std::size_t node = candidates[a].scope_node;
                for (const auto& e : effects_)
                    wall_compliance[a] = e->wall_compliance_mm_per_N(
                        ContactWallView{arc_from_tip_mm(node), candidates[a].region,
                                        warm_start_[node][0], wall_compliance[a]});
                if (!std::isfinite(wall_compliance[a]) || wall_compliance[a] < 0.0) {
                    report.failure = "a truth effect produced an invalid wall compliance";
                    return report;
                }
            }
        for (std::size_t a = 0; a < nc; ++a) {
            const ContactCandidate& ca = candidates[a];
            // The scope's response to the carried forces, already in its free motion.
            Eigen::Vector3d carried_response = Eigen::Vector3d::Zero();
            for (std::size_t b = 0; b < nc; ++b) {
                const ContactCandidate& cb = candidates[b];
                const DelassusPair pair =
                    delassus_pair(ca.frame,
                                  scope_blocks.block<3, 3>(static_cast<Eigen::Index>(3 * a),
                                                           static_cast<Eigen::Index>(3 * b)),
                                  compliance_->point_block(ca.colon_segment, ca.colon_weight,
                                                           cb.colon_segment, cb.colon_weight),
                                  cb.frame);
                carried_response += pair.scope * carried[b];
                const Eigen::Matrix3d& w = pair.total;
                const Eigen::Matrix3d w_local =
                    a == b ? Eigen::Matrix3d(w + wall_compliance[a] * Eigen::Matrix3d::Identity())
                           : w;
                for (std::size_t i = 0; i < 9; ++i)
                    problem.block(a, b)[i] =
                        w_local(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3));
            }
            // Free relative motion over the step: the gap along n; along t, s the scope's free
            // motion relative to the wall returning to rest from where the last forces held it —
            // the colon beam's deflection and the wall's local spring at this node (without the
            // spring's, a sticking contact would slide by compliance x force every step: the
            // friction felt would depend on speed x time step, not on Coulomb's law alone).
            const Eigen::Vector3d colon_last =
                compliance_->point_displacement(ca.colon_segment, ca.colon_weight, colon_forces_);
            // The wall also moved with the last pleating of the colon (telescoping drags the
            // wall along; a sticking scope goes with it). It happened before the step's first part.
            const auto& pleat_motion = pleating_->state().last_motion_mm;
            const Eigen::Vector3d pleated =
                t_start_s != time_s_
                    ? Eigen::Vector3d::Zero()
                    : Eigen::Vector3d((1.0 - ca.colon_weight) * pleat_motion[ca.colon_segment] +
                                      ca.colon_weight * pleat_motion[ca.colon_segment + 1]);
            const Eigen::Vector3d relative = scope_.position(ca.scope_node) -
                                             start.positions[ca.scope_node] + colon_last +
                                             wall_deflection_mm_[ca.scope_node] - pleated;
            // delta = W f + delta_free with the carried forces' scope response taken out: the
            // free motion above already holds it (W f_carried, scope part). A node that began the
            // step in the wall is only asked out of it at kMaxDepenetration_mm_per_s.
            penetration_kept_mm[a] = penetration_allowed_mm(
                ca, start.positions[ca.scope_node] - scope_.position(ca.scope_node), colon_last,
                wall_compliance[a] * std::max(0.0, carried[a].x()), h);
            problem.free_displacement[a] = {
                ca.gap_mm + penetration_kept_mm[a] - carried_response.x(),
                ca.frame.col(1).dot(relative) - carried_response.y(),
                ca.frame.col(2).dot(relative) - carried_response.z()};
            // Sliding speed for the effects: the node's velocity relative to the wall over the last
            // step (the colon's from its displacement now and one step earlier), across the normal.
            double sliding_speed = 0.0;
            if (!effects_.empty()) {
                const Eigen::Vector3d colon_before = compliance_->point_displacement(
                    ca.colon_segment, ca.colon_weight, previous_colon_forces_);
                const Eigen::Vector3d v =
                    velocity_.segment<3>(static_cast<Eigen::Index>(6 * ca.scope_node)) -
                    (colon_last - colon_before) / h;
                const Eigen::Vector3d n = ca.frame.col(0);
                sliding_speed = (v - n.dot(v) * n).norm();
            }
            mu[a] = friction_at(arc_from_tip_mm(ca.scope_node), ca.region, sliding_speed);
            problem.friction[a] = mu[a];
            forces[a] = {carried[a].x(), carried[a].y(), carried[a].z()};
        }
        contact::GaussSeidelSettings<double> gs;
        gs.mode = contact::SweepMode::until_converged;
        gs.max_sweeps = settings_.contact.max_sweeps;
        gs.tolerance = settings_.contact.tolerance_N;
        gs.relaxation = relaxation_;
        const auto solved = contact::solve_contacts(problem, gs, forces);
        report.sweeps = solved.sweeps;
        report.contact_residual_N =
            std::max({solved.residuals.complementarity, solved.residuals.cone_violation,
                      solved.residuals.friction});
        if (solved.status != contact::ContactSolveStatus::converged) {
            std::ostringstream m;
            m << "contact: Gauss-Seidel did not converge in " << solved.sweeps << " sweeps with "
              << nc << " contacts (last change " << solved.last_change << " N > tolerance "
              << settings_.contact.tolerance_N
              << " N); raise solver.contact.max_sweeps or the tolerance";
            report.failure = m.str();
            return report;
        }
        // A contact whose W_aa is not positive definite is ignored by the solver (f = 0) and the
        // scope would pass through the wall there: the step matrix is indefinite (a scope
        // compressed beyond buckling); World::step retries with the material tangent.
        if (solved.degenerate_contacts > 0) {
            report.failure = "contact: " + std::to_string(solved.degenerate_contacts) +
                             " contact(s) with a compliance that is not positive definite (the "
                             "scope's step matrix is indefinite)";
            return report;
        }
        for (std::size_t a = 0; a < nc; ++a)
            if (!std::isfinite(forces[a][0] + forces[a][1] + forces[a][2])) {
                std::ostringstream m;
                m << "contact: non-finite force at scope node " << candidates[a].scope_node
                  << " (colon segment " << candidates[a].colon_segment << ", gap "
                  << candidates[a].gap_mm << " mm, W_nn " << problem.block(a, a)[0]
                  << " mm/N, free motion " << problem.free_displacement[a][1] << ", "
                  << problem.free_displacement[a][2] << " mm)";
                report.failure = m.str();
                return report;
            }
        // 5. Contact correction: the change of the contact forces from those carried.
        for (std::size_t a = 0; a < nc; ++a) {
            const Eigen::Vector3d f(forces[a][0], forces[a][1], forces[a][2]);
            correction.segment<3>(static_cast<Eigen::Index>(6 * candidates[a].scope_node)) =
                candidates[a].frame * (f - carried[a]);
        }
        const Eigen::VectorXd contact_increment = factorization_.solve(correction);
        if (!contact_increment.allFinite()) {
            report.failure = "contact: the correction is not finite";
            return report;
        }
        scope_.apply_increment(contact_increment);
        increment_total += contact_increment;
        last_increment += contact_increment;
        // A node that jumps farther than kMaxNodeStep_mm in one step (1 m/s at 10 ms) is no
        // motion a hand or a colon makes: the linear step left its range, as it does when an
        // indefinite step matrix (a scope compressed beyond buckling) amplifies a mode;
        // World::step retries (a half step, then the material tangent, which always stands).
        for (std::size_t k = 0; geometric_tangent && k < nodes; ++k)
            if (increment_total.segment<3>(static_cast<Eigen::Index>(6 * k)).norm() >
                kMaxNodeStep_mm) {
                report.failure = "the step moved scope node " + std::to_string(k) +
                                 " by more than " + std::to_string(kMaxNodeStep_mm) + " mm";
                return report;
            }
        // Reports: delta = W f + delta_free after the solve.
        std::vector<WorldContact> reports(nc);
        std::vector<ColonPointForce> colon_forces(nc);
        wall_deflection_mm_.assign(nodes, Eigen::Vector3d::Zero());
        for (std::size_t a = 0; a < nc; ++a) {
            std::array<double, 3> delta = problem.free_displacement[a];
            for (std::size_t b = 0; b < nc; ++b)
                for (std::size_t i = 0; i < 3; ++i)
                    for (std::size_t j = 0; j < 3; ++j)
                        delta[i] += problem.block(a, b)[3 * i + j] * forces[b][j];
            const ContactCandidate& c = candidates[a];
            WorldContact& r = reports[a];
            r.scope_node = c.scope_node;
            r.arc_from_tip_mm = arc_from_tip_mm(c.scope_node);
            r.region = c.region;
            r.scope_point_mm = to_body(scope_.position(c.scope_node));
            r.normal = to_body_direction(c.frame.col(0));
            r.normal_force_N = forces[a][0];
            r.tangential_force_N = std::hypot(forces[a][1], forces[a][2]);
            r.force_N = to_body_direction(
                c.frame * Eigen::Vector3d(forces[a][0], forces[a][1], forces[a][2]));
            r.friction_coefficient = mu[a];
            r.driving_angle_rad =
                r.normal_force_N > 0.0 ? std::atan2(r.tangential_force_N, r.normal_force_N) : 0.0;
            r.gap_mm = delta[0] - penetration_kept_mm[a];
            r.slip_mm = to_body_direction(delta[1] * c.frame.col(1) + delta[2] * c.frame.col(2));
            r.state = solved.states[a];
            // The solve's own shortfall: a penetration kept on purpose (the depenetration limit) is
            // not one.
            report.max_penetration_mm = std::max(report.max_penetration_mm, -delta[0]);
            report.friction_work_Nmm += forces[a][1] * delta[1] + forces[a][2] * delta[2];
            colon_forces[a] = {
                c.colon_segment, c.colon_weight,
                -(c.frame * Eigen::Vector3d(forces[a][0], forces[a][1], forces[a][2]))};
            // The wall's local spring under the tangential force on the wall, -f_T (the normal
            // part is measured afresh by the gap every step).
            wall_deflection_mm_[c.scope_node] =
                -wall_compliance[a] * (c.frame * Eigen::Vector3d(0.0, forces[a][1], forces[a][2]));
        }
        contact_reports_ = std::move(reports);
        previous_colon_forces_ = std::move(colon_forces_);
        colon_forces_ = std::move(colon_forces);
    } else {
        contact_reports_.clear();
        previous_colon_forces_ = std::move(colon_forces_);
        colon_forces_.clear();
        wall_deflection_mm_.assign(nodes, Eigen::Vector3d::Zero());
    }
    if (!increment_total.allFinite()) {
        report.failure = "the step produced a non-finite state";
        return report;
    }

    // Handle: reactions of the held DOFs (linearised residual after the correction).
    const Eigen::VectorXd reaction =
        unconstrained_.multiply(last_increment) - last_residual - correction - released;
    double force = command.force_controlled ? command.push_force_N : 0.0;
    double torque = command.torque_controlled ? command.torque_Nmm : 0.0;
    for (std::size_t k = 0; k < nodes; ++k) {
        if (!held[k]) continue;
        if (!command.force_controlled) force += reaction(static_cast<Eigen::Index>(6 * k));
        if (!command.torque_controlled) torque += reaction(static_cast<Eigen::Index>(6 * k + 3));
    }
    handle_force_N_ = force;
    handle_torque_Nmm_ = torque;
    velocity_ = increment_total / h;
    warm_start_.assign(nodes, {0.0, 0.0, 0.0});
    contact_force_N_.assign(nodes, Eigen::Vector3d::Zero());
    for (std::size_t a = 0; a < nc; ++a) {
        warm_start_[candidates[a].scope_node] = forces[a];
        contact_force_N_[candidates[a].scope_node] =
            candidates[a].frame * Eigen::Vector3d(forces[a][0], forces[a][1], forces[a][2]);
    }
    roll_rad_ += wrap_pi(roll_of(scope_.rotation(0)) - wrap_pi(roll_rad_));
    note_effect_forces(loads, loads_end_of, held, increment_total);
    report.contacts = nc;
    report.ok = true;
    return report;
}

}  // namespace scopekin::model

namespace scopekin::model {

void World::note_effect_forces(const std::vector<NodalLoad>& loads,
                               const std::vector<std::size_t>& loads_end_of,
                               const std::vector<bool>& held,
                               const Eigen::VectorXd& increment_total) {
    effect_force_N_.assign(effects_.size(), Eigen::Vector3d::Zero());
    std::size_t first = 0;
    for (std::size_t e = 0; e < loads_end_of.size() && e < effects_.size(); ++e) {
        for (std::size_t i = first; i < loads_end_of[e]; ++i) {
            const NodalLoad& l = loads[i];
            const auto at = static_cast<Eigen::Index>(6 * l.node);
            // At the step's end, as the step applied it: F - K d for a position-following load.
            Eigen::Vector3d force_N = l.force_N;
            if (!held[l.node])
                force_N -=
                    l.stiffness_N_per_mm * rotation_.transpose() * increment_total.segment<3>(at);
            effect_force_N_[e] += rotation_ * force_N;
        }
        first = loads_end_of[e];
    }
}

double World::effect_force_N(const std::string& effect_name) const {
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    for (std::size_t e = 0; e < effects_.size() && e < effect_force_N_.size(); ++e)
        if (effects_[e]->name() == effect_name) total += effect_force_N_[e];
    return total.norm();
}

long World::tracked_colon_segment(std::size_t node) const {
    return node < tracking_.segment.size() ? tracking_.segment[node] : -1;
}

std::pair<double, double> World::centerline_search_window_mm(std::size_t node,
                                                             double search_back_mm) const {
    const long tracked = tracked_colon_segment(node);
    if (tracked < 0) {
        const double expected = insertion_depth_mm() - arc_from_tip_mm(node);
        return {expected - search_back_mm, expected + 5.0};
    }
    const auto segment = static_cast<std::size_t>(tracked);
    const std::size_t reach = tracking_.window_segments + 1;
    const std::size_t last_point = tube_.point_count() - 1;
    const std::size_t first = segment > reach ? segment - reach : 0;
    const std::size_t last = std::min(last_point, segment + reach + 1);
    return {tube_.arc_length_mm(first), tube_.arc_length_mm(last)};
}

StationCompliance World::probe_stations(const std::vector<std::size_t>& nodes,
                                        double search_back_mm) {
    for (std::size_t i = 0; i < nodes.size(); ++i)
        if (nodes[i] >= scope_.node_count() || (i > 0 && nodes[i] <= nodes[i - 1]))
            throw ModelError("probe_stations: scope nodes must be strictly increasing and exist");
    StationCompliance out;
    const std::size_t k = nodes.size();
    out.stations.resize(k);
    out.compliance_mm_per_N =
        Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(3 * k), static_cast<Eigen::Index>(3 * k));
    const double depth = insertion_depth_mm();
    std::vector<Eigen::Vector3d> colon_u;
    compliance_->displacement(colon_forces_, colon_u);
    std::vector<Eigen::Vector3d> colon(colon_rest_mm_.size());
    for (std::size_t i = 0; i < colon.size(); ++i)
        colon[i] = colon_rest_mm_[i] + colon_u[i];
    const auto& points = tube_.points();
    std::vector<Eigen::Matrix3d> frames(k, Eigen::Matrix3d::Identity());
    for (std::size_t a = 0; a < k; ++a) {
        StationProbe& p = out.stations[a];
        p.scope_node = nodes[a];
        const Eigen::Vector3d x = scope_.position(nodes[a]);
        const double expected = depth - arc_from_tip_mm(nodes[a]);
        p.inside = x.x() > 1e-9 && expected > 0.0;
        if (!p.inside) continue;
        double best = std::numeric_limits<double>::infinity();
        const auto [from_mm, to_mm] = centerline_search_window_mm(nodes[a], search_back_mm);
        for (std::size_t j = 0; j + 1 < colon.size(); ++j) {
            if (tube_.arc_length_mm(j + 1) < from_mm || tube_.arc_length_mm(j) > to_mm) continue;
            const Eigen::Vector3d d = colon[j + 1] - colon[j];
            const double w = std::clamp((x - colon[j]).dot(d) / d.squaredNorm(), 0.0, 1.0);
            const double dist = (colon[j] + w * d - x).norm();
            if (dist < best) {
                best = dist;
                p.colon_segment = j;
                p.colon_weight = w;
            }
        }
        const std::size_t j = p.colon_segment;
        const double w = p.colon_weight;
        const Eigen::Vector3d c = colon[j] + w * (colon[j + 1] - colon[j]);
        const Eigen::Vector3d axis = (colon[j + 1] - colon[j]).normalized();
        p.path_mm =
            tube_.arc_length_mm(j) + w * (tube_.arc_length_mm(j + 1) - tube_.arc_length_mm(j));
        const double lumen =
            (1.0 - w) * points[j].inner_radius_mm + w * points[j + 1].inner_radius_mm;
        p.gap_mm = lumen - scope_radius_mm_ - best;
        p.region = points[j].region;
        // n from the scope towards the centerline (the way the wall pushes); when the scope sits on
        // the centerline any direction across the axis will do: take the one towards gravity's opposite.
        Eigen::Vector3d n = c - x;
        n -= n.dot(axis) * axis;
        if (n.norm() < 1e-6) {
            n = -gravity_ - (-gravity_).dot(axis) * axis;
            if (n.norm() < 1e-9) n = axis.unitOrthogonal();
        }
        n.normalize();
        const Eigen::Vector3d t = (axis - axis.dot(n) * n).normalized();
        frames[a].col(0) = n;
        frames[a].col(1) = t;
        frames[a].col(2) = n.cross(t);
        p.frame = rotation_.transpose() * frames[a];
    }
    // Quasi-static tangent with the handle held (position control of depth and roll).
    std::vector<bool> held(scope_.node_count(), false);
    std::size_t first_element = 0;
    for (std::size_t n = 0; n < scope_.node_count(); ++n)
        held[n] = n == 0 || scope_.position(n).x() <= 1e-9;
    while (first_element + 1 < scope_.node_count() && held[first_element + 1])
        ++first_element;
    ScopeBeam::Assembly assembly;
    Eigen::MatrixXd blocks;
    std::vector<std::size_t> inside_nodes;
    std::vector<std::size_t> inside_index;
    for (std::size_t a = 0; a < k; ++a)
        if (out.stations[a].inside) {
            inside_nodes.push_back(nodes[a]);
            inside_index.push_back(a);
        }
    bool formed = inside_nodes.empty();
    for (int tangent = 0; tangent < 2 && !formed; ++tangent) {
        scope_.assemble(assembly, true, nullptr, first_element);
        BlockTridiagonalMatrix system = tangent == 0 ? assembly.tangent : assembly.material_tangent;
        for (std::size_t n = 0; n < scope_.node_count(); ++n)
            if (held[n] || n < first_element)
                for (std::size_t d = 0; d < 6; ++d)
                    system.constrain_dof(6 * n + d);
        SelectedInverse inverse;
        formed = inverse.translational_blocks(system, inside_nodes, blocks);
        // The full tangent of a compressed, buckled shaft is indefinite: its "compliance" would have
        // negative directions. Use the material tangent then.
        if (formed && tangent == 0)
            for (std::size_t a = 0; a < inside_nodes.size() && formed; ++a) {
                const Eigen::Matrix3d diag = blocks.block<3, 3>(static_cast<Eigen::Index>(3 * a),
                                                                static_cast<Eigen::Index>(3 * a));
                formed = diag.trace() > 0.0 && Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(
                                                   0.5 * (diag + diag.transpose()))
                                                       .eigenvalues()
                                                       .minCoeff() > 0.0;
            }
    }
    if (!formed) throw ModelError("probe_stations: the scope's tangent stiffness is singular");
    for (std::size_t ia = 0; ia < inside_index.size(); ++ia)
        for (std::size_t ib = 0; ib < inside_index.size(); ++ib) {
            const std::size_t a = inside_index[ia], b = inside_index[ib];
            const StationProbe& pa = out.stations[a];
            const StationProbe& pb = out.stations[b];
            Eigen::Matrix3d w = frames[a].transpose() *
                                (blocks.block<3, 3>(static_cast<Eigen::Index>(3 * ia),
                                                    static_cast<Eigen::Index>(3 * ib)) +
                                 compliance_->point_block(pa.colon_segment, pa.colon_weight,
                                                          pb.colon_segment, pb.colon_weight)) *
                                frames[b];
            if (a == b)
                w += settings_.contact.wall_compliance_mm_per_N * Eigen::Matrix3d::Identity();
            out.compliance_mm_per_N.block<3, 3>(static_cast<Eigen::Index>(3 * a),
                                                static_cast<Eigen::Index>(3 * b)) = w;
        }
    for (std::size_t a = 0; a < k; ++a)
        if (!out.stations[a].inside)
            out.compliance_mm_per_N
                .block<3, 3>(static_cast<Eigen::Index>(3 * a), static_cast<Eigen::Index>(3 * a))
                .setIdentity();
    return out;
}

}  // namespace scopekin::model
