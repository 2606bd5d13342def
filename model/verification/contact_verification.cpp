#include "model/verification/contact_verification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include "model/colon/bundled_colons.hpp"
#include "model/scope/cf_q160l.hpp"

namespace scopekin::model::contact_verification {
namespace sc = scopekin::contact;
namespace {

constexpr std::size_t kSmall = 20;
using SmallProblem = sc::ContactProblem<double, kSmall>;
using SmallForces = sc::ContactForces<double, kSmall>;

sc::GaussSeidelSettings<double> converge_to(double tolerance) {
    sc::GaussSeidelSettings<double> s;
    s.mode = sc::SweepMode::until_converged;
    s.tolerance = tolerance;
    s.max_sweeps = 20000;
    return s;
}

/// delta = W f + q recomputed with Eigen (independent of the solver's own bookkeeping).
Eigen::VectorXd displacement(const Eigen::MatrixXd& w, const Eigen::VectorXd& q,
                             const SmallForces& f, std::size_t n) {
    Eigen::VectorXd fv(static_cast<Eigen::Index>(3 * n));
    for (std::size_t a = 0; a < n; ++a)
        for (std::size_t k = 0; k < 3; ++k)
            fv(static_cast<Eigen::Index>(3 * a + k)) = f[a][k];
    return w * fv + q;
}

std::unique_ptr<SmallProblem> make_problem(const Eigen::MatrixXd& w, const Eigen::VectorXd& q,
                                           const std::vector<double>& mu) {
    auto p = std::make_unique<SmallProblem>();
    const std::size_t n = mu.size();
    p->contact_count = n;
    for (std::size_t i = 0; i < 3 * n; ++i)
        for (std::size_t j = 0; j < 3 * n; ++j)
            p->delassus_entry(i, j) = w(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
    for (std::size_t a = 0; a < n; ++a) {
        for (std::size_t k = 0; k < 3; ++k)
            p->free_displacement[a][k] = q(static_cast<Eigen::Index>(3 * a + k));
        p->friction[a] = mu[a];
    }
    return p;
}

/// Frictionless normal LCP by enumeration of active sets: 0 <= f ⟂ W f + q >= 0.
Eigen::VectorXd enumerate_lcp(const Eigen::MatrixXd& w, const Eigen::VectorXd& q) {
    const auto n = q.size();
    for (unsigned mask = 0; mask < (1U << n); ++mask) {
        std::vector<Eigen::Index> active;
        for (Eigen::Index i = 0; i < n; ++i)
            if (mask & (1U << i)) active.push_back(i);
        Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
        if (!active.empty()) {
            const auto k = static_cast<Eigen::Index>(active.size());
            Eigen::MatrixXd ws(k, k);
            Eigen::VectorXd qs(k);
            for (Eigen::Index i = 0; i < k; ++i) {
                qs(i) = q(active[static_cast<std::size_t>(i)]);
                for (Eigen::Index j = 0; j < k; ++j)
                    ws(i, j) =
                        w(active[static_cast<std::size_t>(i)], active[static_cast<std::size_t>(j)]);
            }
            const Eigen::VectorXd fs = ws.fullPivLu().solve(-qs);
            for (Eigen::Index i = 0; i < k; ++i)
                f(active[static_cast<std::size_t>(i)]) = fs(i);
        }
        const Eigen::VectorXd d = w * f + q;
        if (f.minCoeff() >= -1e-12 && d.minCoeff() >= -1e-12) return f;
    }
    return Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
}

/// Random SPD Delassus operator W = J M^-1 J^T + eps I of n contacts (3n rows, 3n + 6 DOFs).
Eigen::MatrixXd random_delassus(std::mt19937& rng, std::size_t n) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const auto rows = static_cast<Eigen::Index>(3 * n), cols = rows + 6;
    Eigen::MatrixXd j(rows, cols);
    for (Eigen::Index r = 0; r < rows; ++r)
        for (Eigen::Index c = 0; c < cols; ++c)
            j(r, c) = u(rng);
    Eigen::VectorXd inverse_mass(cols);
    for (Eigen::Index c = 0; c < cols; ++c)
        inverse_mass(c) = 0.5 + 0.5 * std::abs(u(rng));
    return j * inverse_mass.asDiagonal() * j.transpose() +
           1e-3 * Eigen::MatrixXd::Identity(rows, rows);
}

double arc_position_mm(const ColonTube& tube, const Eigen::Vector3d& x) {
    double best = std::numeric_limits<double>::infinity(), arc = 0.0;
    const auto& p = tube.points();
    for (std::size_t j = 0; j + 1 < p.size(); ++j) {
        const Eigen::Vector3d ab = p[j + 1].position_mm - p[j].position_mm;
        const double w = std::clamp((x - p[j].position_mm).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
        const double d = (x - p[j].position_mm - w * ab).norm();
        if (d < best) {
            best = d;
            arc = tube.arc_length_mm(j) + w * ab.norm();
        }
    }
    return arc;
}

}  // namespace

std::vector<VerificationRow> lcp_rows() {
    std::vector<VerificationRow> rows;
    // Single contact, W = diag(2, 1, 1) mm/N, mu = 0.25: hand-worked answers.
    //  separation: d = (+1, 0.3, 0)   -> f = 0
    //  stick:      d = (-2, 0.1, 0)   -> f = -W^-1 d = (1, -0.1, 0); |f_T| = 0.1 <= 0.25
    //  slip:       d = (-2, 3, 0)     -> f_n = 1 (delta_n = 0), f_t = -mu f_n = -0.25, delta_t = 2.75 > 0
    struct Case {
        const char* name;
        Eigen::Vector3d d;
        Eigen::Vector3d f;
    };
    const Case cases[] = {{"separation", {1.0, 0.3, 0.0}, {0.0, 0.0, 0.0}},
                          {"stick", {-2.0, 0.1, 0.0}, {1.0, -0.1, 0.0}},
                          {"slip", {-2.0, 3.0, 0.0}, {1.0, -0.25, 0.0}}};
    for (const Case& c : cases) {
        Eigen::MatrixXd w = Eigen::Vector3d(2.0, 1.0, 1.0).asDiagonal();
        auto p = make_problem(w, c.d, {0.25});
        SmallForces f{};
        sc::solve_contacts(*p, converge_to(1e-12), f);
        const double err = (Eigen::Vector3d(f[0][0], f[0][1], f[0][2]) - c.f).norm();
        rows.push_back(make_row(std::string("lcp/single_contact_") + c.name + "/force_error", 0.0,
                                err, err, 1e-9, "N", "abs"));
    }
    // 1000 random well-posed problems, n = 2..20, mu in [0, 1], tolerance 1e-9 N on the change.
    std::mt19937 rng(20131121);
    double worst = 0.0, worst_work = -std::numeric_limits<double>::infinity();
    std::size_t not_converged = 0;
    std::uniform_real_distribution<double> u(-1.0, 1.0), mu01(0.0, 1.0);
    for (int trial = 0; trial < 1000; ++trial) {
        const std::size_t n = 2 + static_cast<std::size_t>(trial % 19);
        const Eigen::MatrixXd w = random_delassus(rng, n);
        Eigen::VectorXd q(static_cast<Eigen::Index>(3 * n));
        for (Eigen::Index i = 0; i < q.size(); ++i)
            q(i) = u(rng);
        std::vector<double> mu(n);
        for (double& m : mu)
            m = mu01(rng);
        auto p = make_problem(w, q, mu);
        SmallForces f{};
        const auto r = sc::solve_contacts(*p, converge_to(1e-9), f);
        if (r.status != sc::ContactSolveStatus::converged) ++not_converged;
        const Eigen::VectorXd d = displacement(w, q, f, n);
        for (std::size_t a = 0; a < n; ++a) {
            const auto i = static_cast<Eigen::Index>(3 * a);
            const double fn = f[a][0], ft = std::hypot(f[a][1], f[a][2]);
            // Signorini natural map in N, cone violation in N (independent recomputation).
            worst = std::max(
                {worst, std::abs(std::min(fn, d(i) / w(i, i))), std::max(0.0, ft - mu[a] * fn)});
            worst_work = std::max(worst_work, f[a][1] * d(i + 1) + f[a][2] * d(i + 2));
        }
    }
    rows.push_back(make_row("lcp/random_1000/not_converged", 0.0,
                            static_cast<double>(not_converged), static_cast<double>(not_converged),
                            0.0, "problems", "abs"));
    rows.push_back(make_row("lcp/random_1000/max_signorini_or_cone_residual", 0.0, worst, worst,
                            1e-7, "N", "abs"));
    rows.push_back(make_row("lcp/random_1000/max_friction_power", 0.0, worst_work,
                            std::max(0.0, worst_work), 1e-9, "N mm", "abs"));
    // Frictionless, n = 1..6 normal contacts: Gauss-Seidel against active-set enumeration.
    double worst_enum = 0.0;
    for (int trial = 0; trial < 200; ++trial) {
        const std::size_t n = 1 + static_cast<std::size_t>(trial % 6);
        const Eigen::MatrixXd w3 = random_delassus(rng, n);
        Eigen::VectorXd q(static_cast<Eigen::Index>(3 * n));
        for (Eigen::Index i = 0; i < q.size(); ++i)
            q(i) = u(rng);
        auto p = make_problem(w3, q, std::vector<double>(n, 0.0));
        SmallForces f{};
        sc::solve_contacts(*p, converge_to(1e-13), f);
        const auto k = static_cast<Eigen::Index>(n);
        Eigen::MatrixXd wn(k, k);
        Eigen::VectorXd qn(k);
        for (Eigen::Index a = 0; a < k; ++a) {
            qn(a) = q(3 * a);
            for (Eigen::Index b = 0; b < k; ++b)
                wn(a, b) = w3(3 * a, 3 * b);
        }
        const Eigen::VectorXd reference = enumerate_lcp(wn, qn);
        for (Eigen::Index a = 0; a < k; ++a)
            worst_enum =
                std::max(worst_enum, std::abs(reference(a) - f[static_cast<std::size_t>(a)][0]));
    }
    rows.push_back(make_row("lcp/frictionless_vs_enumeration/max_force_difference", 0.0, worst_enum,
                            worst_enum, 1e-8, "N", "abs"));
    return rows;
}

PushResult push_through_tube(double bend_angle_rad, double mu, double duration_s, double window_s) {
    const double scope_radius = cf_q160l::kRadius_mm;
    const double bend_radius = 40.0, lead = 150.0, lumen = 15.0;
    const bool straight = bend_angle_rad <= 0.0;
    // Straight: a rigid tube (descending colon, clamped); bend: sigmoid-like, on its mesentery.
    const ColonTube tube = straight
                               ? straight_tube(700.0, lumen, ColonRegion::descending, scope_radius)
                               : single_bend(lead, bend_radius, bend_angle_rad, lumen,
                                             ColonRegion::sigmoid, scope_radius);
    ScopeSpec spec;
    spec.length_mm = 600.0;
    spec.elements = 60;
    spec.radius_mm = scope_radius;
    spec.section = cf_q160l::section();
    WorldSettings settings;
    settings.gravity_mm_per_s2.setZero();
    settings.initial_insertion_mm = 50.0;
    settings.contact.friction_coefficient = mu;
    World world(spec, tube, default_colon_properties(), settings);
    PushResult out;
    const double speed = 50.0, h = settings.time_step_s;
    const auto steps = static_cast<std::size_t>(std::lround(duration_s / h));
    const auto window_start = steps - static_cast<std::size_t>(std::lround(window_s / h));
    const Eigen::Vector3d bend_centre(lead, bend_radius, 0.0);
    const std::size_t tip = world.scope_node_count() - 1;
    double tip_arc_start = 0.0, depth_start = 0.0;
    HandleCommand command;
    for (std::size_t i = 0; i < steps; ++i) {
        if (i == window_start) {
            tip_arc_start = arc_position_mm(tube, world.node_position_mm(tip));
            depth_start = world.insertion_depth_mm();
        }
        command.insertion_mm =
            settings.initial_insertion_mm + speed * h * static_cast<double>(i + 1);
        const WorldStepReport r = world.step(command);
        if (!r.ok) {
            out.failure = r.failure;
            return out;
        }
        ++out.steps;
        out.max_penetration_mm = std::max(out.max_penetration_mm, r.max_penetration_mm);
        out.max_friction_work_Nmm = std::max(out.max_friction_work_Nmm, r.friction_work_Nmm);
        out.max_lateral_tip_deviation_mm = std::max(out.max_lateral_tip_deviation_mm,
                                                    world.node_position_mm(tip).tail<2>().norm());
        for (const WorldContact& c : world.contacts()) {
            out.max_normal_force_N = std::max(out.max_normal_force_N, c.normal_force_N);
            if (c.scope_node == tip && i >= window_start) out.tip_sliding_mm += c.slip_mm.norm();
            // The leading part of the scope (the tip's contacts) against the bend's walls.
            if (straight || c.normal_force_N <= 1e-6 || c.scope_node != tip) continue;
            // In the bend (beyond the entry lead, before the exit): which wall does the scope touch?
            const Eigen::Vector3d rel = c.scope_point_mm - bend_centre;
            const double angle = std::atan2(rel.x(), -rel.y());
            if (angle <= 0.0 || angle >= bend_angle_rad) continue;
            ++out.loaded_contacts_in_bend;
            if (rel.norm() > bend_radius) ++out.loaded_contacts_on_outer_wall;
        }
    }
    out.handle_advance_mm = world.insertion_depth_mm() - depth_start;
    out.tip_advance_mm = arc_position_mm(tube, world.node_position_mm(tip)) - tip_arc_start;
    (void)tip_arc_start;
    out.handle_force_N = world.handle_force_N();
    for (const WorldContact& c : world.contacts())
        if (c.scope_node == tip && c.normal_force_N > 0.0) {
            out.tip_driving_angle_rad = c.driving_angle_rad;
            out.tip_sticking = c.state == sc::ContactState::sticking;
        }
    out.ok = true;
    return out;
}

std::vector<VerificationRow> world_rows() {
    std::vector<VerificationRow> rows;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    auto value_or_nan = [&](const PushResult& r, double v) { return r.ok ? v : nan; };
    // Straight rigid tube, no gravity: the scope slides down the axis without touching the wall.
    const PushResult straight = push_through_tube(0.0, 0.25, 4.0, 1.0);
    rows.push_back(make_row("world/straight_tube/max_contact_force", 0.0,
                            value_or_nan(straight, straight.max_normal_force_N),
                            value_or_nan(straight, straight.max_normal_force_N), 1e-9, "N", "abs"));
    rows.push_back(make_row("world/straight_tube/tip_off_axis", 0.0,
                            value_or_nan(straight, straight.max_lateral_tip_deviation_mm),
                            value_or_nan(straight, straight.max_lateral_tip_deviation_mm), 1e-6,
                            "mm", "abs"));
    // 115 degree bend, mu = 0.25: the scope is pressed on the outer wall.
    const PushResult bend = push_through_tube(2.0, 0.25, 6.0, 1.5);
    const double outer = bend.loaded_contacts_in_bend > 0
                             ? static_cast<double>(bend.loaded_contacts_on_outer_wall) /
                                   static_cast<double>(bend.loaded_contacts_in_bend)
                             : nan;
    rows.push_back(make_row("world/bend/share_of_loaded_contacts_on_outer_wall", 1.0,
                            value_or_nan(bend, outer), value_or_nan(bend, 1.0 - outer), 0.0, "1",
                            "abs"));
    rows.push_back(make_row("world/bend/max_penetration", 0.0,
                            value_or_nan(bend, bend.max_penetration_mm),
                            value_or_nan(bend, bend.max_penetration_mm), 1e-4, "mm", "abs"));
    rows.push_back(make_row("world/bend/max_friction_work_per_step", 0.0,
                            value_or_nan(bend, bend.max_friction_work_Nmm),
                            value_or_nan(bend, bend.max_friction_work_Nmm), 1e-5, "N mm", "abs"));
    // (A positive value can only come from the 1e-6 N solver tolerance times slips of a few mm.)
    // Self-locking (thesis 2.2.1): same bend, mu = 1.2 (friction angle 50 deg) vs mu = 0.05 (3 deg),
    // 4.5 s of push, the last 1.5 s measured: at mu = 1.2 the tip hooks at 2.7 s and stays stuck
    // while the handle force climbs to ~30 N. Pushed on, the scope (some 30 contacts, ~30 N in
    // compression) buckles into loop shapes that depend on the step size, and dragging the mobile
    // wall can raise the tip's driving angle to the friction angle: at steps of 2-10 ms the handle
    // force over 4.5-6 s averaged 19-34 N, and the tip broke free at 10 and at 2 ms but not at
    // 2.5-8 ms. Before 4.5 s the tip held at every step size tried.
    const PushResult locked = push_through_tube(2.0, 1.2, 4.5, 1.5);
    const PushResult sliding = push_through_tube(2.0, 0.05, 4.5, 1.5);
    // The tip's sliding along the wall (relative to the colon, which the stuck tip drags along)
    // over the last 1.5 s, per mm of handle advance: 0 when self-locked.
    const double locked_ratio = locked.tip_sliding_mm / locked.handle_advance_mm;
    const double sliding_ratio = sliding.tip_sliding_mm / sliding.handle_advance_mm;
    rows.push_back(make_row("world/self_locking/mu_1.2/tip_sliding_over_handle_advance", 0.0,
                            value_or_nan(locked, locked_ratio),
                            value_or_nan(locked, std::abs(locked_ratio)), 0.02, "1", "abs"));
    rows.push_back(make_row("world/self_locking/mu_1.2/tip_contact_sticking", 1.0,
                            value_or_nan(locked, locked.tip_sticking ? 1.0 : 0.0),
                            value_or_nan(locked, locked.tip_sticking ? 0.0 : 1.0), 0.0, "1",
                            "abs"));
    const double beta_locked = std::atan(1.2);
    rows.push_back(make_row(
        "world/self_locking/mu_1.2/driving_angle_minus_friction_angle", 0.0,
        value_or_nan(locked, (locked.tip_driving_angle_rad - beta_locked) * 180.0 / M_PI),
        value_or_nan(locked,
                     std::max(0.0, locked.tip_driving_angle_rad - beta_locked) * 180.0 / M_PI),
        0.0, "deg", "abs"));
    rows.push_back(make_row("world/self_locking/mu_1.2/handle_force", 0.0,
                            value_or_nan(locked, locked.handle_force_N), 0.0, nan, "N", "info"));
    rows.push_back(make_row("world/self_locking/mu_0.05/tip_sliding_over_handle_advance", 1.0,
                            value_or_nan(sliding, sliding_ratio),
                            value_or_nan(sliding, std::abs(sliding_ratio - 1.0)), 0.3, "1", "abs"));
    rows.push_back(make_row(
        "world/self_locking/mu_0.05/tip_driving_angle", std::atan(0.05) * 180.0 / M_PI,
        value_or_nan(sliding, sliding.tip_driving_angle_rad * 180.0 / M_PI),
        value_or_nan(sliding,
                     std::abs(sliding.tip_driving_angle_rad - std::atan(0.05)) * 180.0 / M_PI),
        1e-3, "deg", "abs"));
    rows.push_back(make_row("world/self_locking/mu_0.05/handle_force", 0.0,
                            value_or_nan(sliding, sliding.handle_force_N), 0.0, nan, "N", "info"));
    return rows;
}

}  // namespace scopekin::model::contact_verification
