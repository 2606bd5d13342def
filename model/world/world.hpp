#pragma once
// The world: the scope inside the colon, stepped in time (thesis 5.3, model/PHYSICS.md §5).
// Every step of h:
//   1. free motion: the scope's implicit Euler step (M/h^2 + C/h + K_T) d = r with the handle's
//      prescribed motion, gravity and handle loads, no contact (linearised: one Newton
//      iteration by default, as SOFA's implicit Euler the thesis used; more on request);
//   2. contact detection at the free configuration against the colon at rest;
//   3. Delassus operator W = H (A^-1 + K_c^-1) H^T on the contact frames (Eq. 4.20, 4.24): the
//      scope's part from selected blocks of A^-1, the colon's from its precomputed compliance;
//   4. contact forces from the LCP with Coulomb friction (Eq. 4.19-4.23) by the one
//      Gauss-Seidel solver (firmware/contact/gauss_seidel_contact.hpp), warm-started;
//   5. contact correction: d += A^-1 H^T f; the colon takes u_c = K_c^-1 (-H^T f).
//
// The handle. The scope's node 0 is the handle end, the last node the tip. Outside the body
// the shaft is held straight on the entry axis (the line through the anus along the colon's
// first segment) by the physician's hand and the sensor box: every node that has not passed
// the anus is prescribed on that axis. Insertion depth (mm of scope past the anus) and roll
// (rad about the entry axis) are either prescribed (advance, withdraw, hold, dither, rotate) or
// free with an applied push force / torque at the handle. The handle force is the axial force
// the hand applies (support reactions along the axis, or the applied force), positive pushing
// in; the handle torque likewise about the axis.
//
// Frames. Inputs and outputs are in the colon's (body) frame. Inside, the world computes in a
// frame with the anus at the origin and the entry axis along +x, so that the handle's sliding
// and rolling freedoms are single global DOFs.
#include <Eigen/Dense>
#include <memory>
#include <string>
#include <vector>

#include "contact/gauss_seidel_contact.hpp"  // firmware/: the one Gauss-Seidel solver
#include "model/beam/scope_beam.hpp"
#include "model/colon/colon_compliance.hpp"
#include "model/colon/colon_pleating.hpp"
#include "model/colon/colon_tube.hpp"
#include "model/contact/contact_detection.hpp"
#include "model/linalg/selected_inverse.hpp"
#include "model/solvers/rayleigh_damping.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model {

/// Capacity of the contact problem (simultaneous contacts). Under gravity a scope lies on the
/// colon wall along most of its inserted length, so the reference model makes room for one
/// contact per node of a 1.7 m scope in 1 cm elements (and more); the solver's work grows with
/// the contacts actually present, not with the capacity. Beyond it the closest are kept and the
/// rest are counted as dropped.
inline constexpr std::size_t kMaxWorldContacts = 256;

/// Friction coefficient on a stretch of the scope, measured from the tip [mm].
struct FrictionZone {
    double from_tip_mm = 0;
    double to_tip_mm = 0;
    double coefficient = 0.25;
};

struct WorldContactSettings {
    double activation_distance_mm = 2.0;       ///< nodes closer to the wall enter the LCP
    double friction_coefficient = 0.25;        ///< thesis 5.3 value; default for the whole scope
    std::vector<FrictionZone> friction_zones;  ///< overrides along the scope (later zones win)
    /// Local compliance of the colon wall at a contact [mm/N], isotropic, added to W_aa: the wall's
    /// own indentation, which the beam colon (no radial deformation, thesis 4.3) leaves out. Order
    /// of magnitude of a soft layer pressed over one node's length l: 1 / (E l) with the sigmoid's
    /// E = 0.36 N/mm^2 (Table 4.6) and l = 10 mm gives 0.28 mm/N. It also keeps W_aa well
    /// conditioned where the colon is clamped (rigid), which Gauss-Seidel needs to converge fast.
    double wall_compliance_mm_per_N = 0.28;
    double tolerance_N = 1e-6;  ///< Gauss-Seidel: largest force change per sweep
    std::size_t max_sweeps = 2000;
    /// Gauss-Seidel over-relaxation omega in (0, 2); 1 = plain Gauss-Seidel.
    double relaxation = 1.0;
    void validate() const;  ///< throws ModelError naming the field
};

struct ScopeSpec {
    double length_mm = 1700.0;
    std::size_t elements = 170;
    double radius_mm = 6.65;
    BeamSection section;  ///< all elements (effects may change them)
};

struct WorldSettings {
    double time_step_s = 0.01;  ///< [0.001, 0.033] s
    RayleighDamping damping = RayleighDamping::thesis_cf_q160l();
    int newton_iterations = 1;  ///< of the free motion; 1 = linearly implicit Euler
    Eigen::Vector3d gravity_mm_per_s2{0.0, 0.0,
                                      -9810.0};  ///< body frame (default colon: patient supine)
    double initial_insertion_mm =
        0.0;  ///< scope past the anus at t = 0, straight on the entry axis
    WorldContactSettings contact;
    TelescopingLaw
        telescoping;  ///< the mobile stretches pleat along the scope (colon_pleating.hpp)
    void validate() const;
};

/// What the hand does over the coming step (values at the end of the step).
struct HandleCommand {
    bool force_controlled = false;  ///< axial: push force applied instead of depth prescribed
    double insertion_mm = 0;        ///< prescribed depth (position control)
    double push_force_N = 0;        ///< applied force along the entry axis, + = in (force control)
    bool torque_controlled = false;
    double roll_rad = 0;    ///< prescribed roll about the entry axis
    double torque_Nmm = 0;  ///< applied torque about the entry axis (torque control)
};

/// A scope node seen from the colon, and the quasi-static compliance between such nodes
/// (World::probe_stations): what the firmware's reduced model is built from (model/reduction).
struct StationProbe {
    std::size_t scope_node = 0;
    double path_mm = 0;  ///< arc length along the colon centerline of the closest point
    std::size_t colon_segment = 0;
    double colon_weight = 0;
    double gap_mm = 0;  ///< lumen radius - scope radius - distance from the centerline
    ColonRegion region = ColonRegion::rectum;
    Eigen::Matrix3d frame = Eigen::Matrix3d::
        Identity();       ///< columns n (wall -> scope), t (along the colon), s; body frame
    bool inside = false;  ///< past the anus
};
struct StationCompliance {
    std::vector<StationProbe> stations;
    /// 3k x 3k, blocks (a, b) in the frames of a (rows) and b (columns) [mm/N]: the quasi-static
    /// tangent compliance of the scope (handle held) + the colon's compliance at the closest
    /// centerline points + the wall compliance on the diagonal blocks. Rows/columns of stations
    /// outside the body are zero except 1 on the diagonal.
    Eigen::MatrixXd compliance_mm_per_N;
};

/// One contact after a step, in the body frame.
struct WorldContact {
    std::size_t scope_node = 0;
    double arc_from_tip_mm = 0;
    ColonRegion region = ColonRegion::rectum;
    Eigen::Vector3d scope_point_mm = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< wall -> scope
    double normal_force_N = 0;
    double tangential_force_N = 0;
    Eigen::Vector3d force_N =
        Eigen::Vector3d::Zero();  ///< the wall's force on the scope (normal + friction)
    double friction_coefficient = 0;
    /// Driving-force angle alpha = atan(|f_T| / f_n) (thesis 2.2.1); stick needs alpha < atan(mu).
    double driving_angle_rad = 0;
    double gap_mm = 0;  ///< after the correction (linearised); < 0 = penetration
    Eigen::Vector3d slip_mm =
        Eigen::Vector3d::Zero();  ///< relative tangential motion over the step
    contact::ContactState state = contact::ContactState::separated;
};

struct WorldStepReport {
    bool ok = false;
    std::string failure;  ///< why the step failed (the world is left as before the step)
    std::size_t contacts = 0;
    std::size_t dropped_contacts = 0;  ///< candidates beyond kMaxWorldContacts (closest kept)
    std::size_t sweeps = 0;
    double contact_residual_N =
        0;  ///< max of the solver's complementarity, cone, friction residuals
    double max_penetration_mm = 0;  ///< linearised, after the correction, beyond what was kept
                                    ///< on purpose (kMaxDepenetration_mm_per_s, world.cpp)
    double friction_work_Nmm =
        0;  ///< sum f_T . slip over contacts: <= 0 (friction only dissipates)
    bool material_tangent_fallback =
        false;                   ///< the full tangent failed; the step used the material one
    bool under_relaxed = false;  ///< Gauss-Seidel cycled; the step was solved under-relaxed
    std::size_t substeps = 1;    ///< 1, or 2^k when the full tangent needed k halvings of the step
};

class World {
public:
    /// Builds the colon (structure, compliance) and the straight scope on the entry axis, tip at
    /// `settings.initial_insertion_mm` past the anus. Throws ModelError naming the problem for bad
    /// settings, a colon that is not held, or an initial insertion that crosses the wall.
    World(const ScopeSpec& scope, const ColonTube& colon,
          const std::array<ColonRegionProperties, 8>& properties, WorldSettings settings,
          std::vector<std::shared_ptr<const WorldEffect>> effects = {});

    /// Advances by one time step. A failed step (singular system, non-finite state, contact solver
    /// not converged) leaves the world unchanged and says why.
    WorldStepReport step(const HandleCommand& command);

    double time_s() const { return time_s_; }
    double time_step_s() const { return settings_.time_step_s; }
    double insertion_depth_mm() const;
    double roll_rad() const { return roll_rad_; }
    double handle_force_N() const { return handle_force_N_; }
    double handle_torque_Nmm() const { return handle_torque_Nmm_; }
    /// |net force| [N] that the truth effects of this name put on the scope over the last step
    /// (the vector sum of their nodal loads, as applied at the step's end; 0 without such an
    /// effect): e.g. "abdominal_pressure", the assistant's hand as the scope feels it.
    double effect_force_N(const std::string& effect_name) const;
    double scope_length_mm() const { return length_mm_; }
    std::size_t scope_node_count() const { return scope_.node_count(); }
    double arc_from_tip_mm(std::size_t node) const {
        return length_mm_ - scope_.arc_length_mm(node);
    }
    /// Scope node position in the body frame [mm]; node 0 = handle, last = tip.
    Eigen::Vector3d node_position_mm(std::size_t node) const;
    /// Node velocity in the body frame [mm/s].
    Eigen::Vector3d node_velocity_mm_per_s(std::size_t node) const;
    /// Scope axis direction at a node (body frame).
    Eigen::Vector3d node_axis(std::size_t node) const;
    const std::vector<WorldContact>& contacts() const { return contact_reports_; }
    /// Colon centerline node positions now (at rest + displacement under the contact forces), body frame.
    std::vector<Eigen::Vector3d> colon_positions_mm() const;
    /// One of them (cheaper than all).
    Eigen::Vector3d colon_position_mm(std::size_t node) const;
    const ColonTube& colon() const { return body_tube_; }
    /// Telescoping: the pleated fraction of each mobile stretch (colon_pleating.hpp).
    const ColonPleating& telescoping() const { return *pleating_; }
    /// The scope in the computation frame (anus at the origin, entry axis +x), for tests.
    const ScopeBeam& scope_computation_frame() const { return scope_; }
    /// The centerline segment the contact detection last placed a scope node on (its tracked
    /// search at the start of the last step; contact_detection.hpp), -1 before the first step or
    /// while the node is outside the body.
    long tracked_colon_segment(std::size_t node) const;
    /// The colon coordinates [from, to] (rest arc length, mm) in which a node's closest centerline
    /// point is searched. Where the contact detection tracks the node: its tracked segment and the
    /// tracking window around it plus one segment (about +-4 segments), so the place follows the
    /// node continuously along the colon, as the contact model sees it, and never jumps to another
    /// turn of a loop that lies closer in space. Untracked: [depth - arc_from_tip -
    /// search_back_mm, depth - arc_from_tip + 5 mm] (a shaft cannot be further along the colon
    /// than its length allows).
    std::pair<double, double> centerline_search_window_mm(std::size_t node,
                                                          double search_back_mm) const;
    /// The given scope nodes (strictly increasing) against the colon in its current shape: where
    /// they are along the centerline and the quasi-static compliance between them (K_T^-1 of the
    /// scope with the handle held, material tangent where the full one is indefinite). Each node's
    /// closest centerline point is searched within centerline_search_window_mm.
    StationCompliance probe_stations(const std::vector<std::size_t>& nodes,
                                     double search_back_mm = 400.0);
    /// Kinetic + strain energy of the scope [N mm] and its potential energy in gravity.
    double scope_energy_Nmm() const;

    /// Everything that changes from step to step (the scope's configuration and velocity, the
    /// contacts, the colon's loads, time, roll, the handle's reactions), without the parameters:
    /// a world built from the same scope and colon, with other effects, continues from it. The
    /// discrepancy workflow restarts candidate models from a baseline's states this way.
    struct State {
        double time_s = 0;
        std::size_t steps_taken = 0;
        double roll_rad = 0;
        double handle_force_N = 0;
        double handle_torque_Nmm = 0;
        ScopeBeam::Configuration scope;
        Eigen::VectorXd velocity;
        std::vector<ColonPointForce> colon_forces, previous_colon_forces;
        std::vector<WorldContact> contacts;
        std::vector<std::array<double, 3>> warm_start;
        std::vector<Eigen::Vector3d> wall_deflection_mm;
        std::vector<Eigen::Vector3d> contact_force_N;
        CenterlineTracking tracking;
        ColonPleating::State telescoping;
        std::vector<Eigen::Vector3d> pleated_tube_mm;  ///< the effects' view of the pleated colon
    };
    State state() const;
    /// Continues from `saved`. Throws ModelError when it is another scope's or colon's (node counts
    /// differ) or the step size differs (time is counted in steps).
    void restore(const State& saved);

private:
    /// Keeps each effect's net load of the step just accepted (effect_force_N).
    void note_effect_forces(const std::vector<NodalLoad>& loads,
                            const std::vector<std::size_t>& loads_end_of,
                            const std::vector<bool>& held, const Eigen::VectorXd& increment_total);
    using Problem = contact::ContactProblem<double, kMaxWorldContacts>;
    using Forces = contact::ContactForces<double, kMaxWorldContacts>;

    Eigen::Vector3d to_body(const Eigen::Vector3d& x) const {
        return anus_ + rotation_.transpose() * x;
    }
    Eigen::Vector3d to_body_direction(const Eigen::Vector3d& v) const {
        return rotation_.transpose() * v;
    }
    /// Friction coefficient at a contact: scenario value, zones, then the effects' hooks.
    double friction_at(double arc_from_tip_mm, ColonRegion region,
                       double sliding_speed_mm_per_s) const;
    /// One step of `h` s from `t_start_s` with the full tangent; where that fails, as two half
    /// steps (kMaxStepHalvings deep). Leaves the world as before and fails when that fails too.
    WorldStepReport advance_with_full_tangent(const HandleCommand& command, double h,
                                              double t_start_s, int halvings);
    /// The command halfway from the present handle state to `command` (position and roll; applied
    /// force and torque are held over the whole step).
    HandleCommand halfway_command(const HandleCommand& command) const;
    WorldStepReport attempt(const HandleCommand& command, bool geometric_tangent, double h,
                            double t_start_s);
    /// The last resort of World::step: the step again with Gauss-Seidel under-relaxed.
    WorldStepReport attempt_under_relaxed(const HandleCommand& command);

    WorldSettings settings_;
    double relaxation_ = 1.0;  // Gauss-Seidel's omega for this attempt (settings_ unless retried)
    std::vector<std::shared_ptr<const WorldEffect>> effects_;
    Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();  // body -> computation
    Eigen::Vector3d anus_ = Eigen::Vector3d::Zero();          // body frame
    ColonTube body_tube_;
    ColonTube tube_;  // computation frame
    std::vector<Eigen::Vector3d> colon_rest_mm_;
    std::unique_ptr<ColonCompliance> compliance_;
    std::unique_ptr<ColonPleating> pleating_;       // the rest shape of the mobile stretches
    std::unique_ptr<ColonTube> pleated_body_tube_;  // body frame, for effects; null = unpleated
    std::vector<Eigen::Vector3d> pleated_tube_mm_;  // the rest shape it was built from
    std::vector<Eigen::Vector3d> colon_rest_at_start_mm_;  // unpleated
    static constexpr double kTubeRefresh_mm = 1.0;
    void refresh_pleated_tube(bool always);
    ScopeBeam scope_;
    double length_mm_ = 0;
    double scope_radius_mm_ = 0;
    Eigen::Vector3d gravity_ = Eigen::Vector3d::Zero();  // computation frame

    double time_s_ = 0;
    std::size_t steps_taken_ = 0;
    double roll_rad_ = 0;
    double handle_force_N_ = 0;
    double handle_torque_Nmm_ = 0;
    std::vector<Eigen::Vector3d> effect_force_N_;  ///< per effects_ entry, world frame
    Eigen::VectorXd velocity_;
    std::vector<ColonPointForce> colon_forces_;  // on the colon, computation frame
    std::vector<ColonPointForce>
        previous_colon_forces_;  // one step earlier: the wall's velocity for effects
    std::vector<WorldContact> contact_reports_;
    std::vector<std::array<double, 3>> warm_start_;  // last contact force (n, t, s) per scope node
    /// Per scope node: the tangential deflection of the wall's local spring under the last step's
    /// contact force [mm], computation frame (zero where there was no contact). A sticking contact
    /// keeps its wall loaded: the next step starts from it (see World::step, "Free relative
    /// motion").
    std::vector<Eigen::Vector3d> wall_deflection_mm_;
    /// Per scope node: the last step's contact force on the scope [N], computation frame. The
    /// next step's free motion carries it (see World::attempt, "Free motion").
    std::vector<Eigen::Vector3d> contact_force_N_;
    CenterlineTracking tracking_;

    // Work storage reused every step.
    ScopeBeam::Assembly assembly_;
    BlockTridiagonalMatrix mass_, damping_, system_, unconstrained_;
    BlockTridiagonalSolver factorization_;
    SelectedInverse selected_inverse_;
    std::unique_ptr<Problem> problem_;
    std::unique_ptr<Forces> forces_;
};

}  // namespace scopekin::model
