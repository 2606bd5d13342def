// Coulomb friction in the world model, against physics rather than the code's earlier output:
//  * static limit: a scope lying on a fixed wall stays put under an axial push below mu * N (its
//    drift <= 1e-3 mm/s over 10 s) and slides above it;
//  * rate independence: the force to pull a scope slowly back through a frictional bend is the
//    same whatever the time step (2, 5, 10 ms) and the speed (2, 5, 20 mm/s), within 3 %.
// The local wall compliance (WorldContactSettings::wall_compliance_mm_per_N) is in play in both:
// a sticking contact loads the wall's spring, and the spring must not give back every step.
#include <gtest/gtest.h>

#include <cmath>

#include "model/colon/bundled_colons.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/world/world.hpp"

namespace scopekin::model {
namespace {

ScopeSpec scope_of(double length_mm) {
    ScopeSpec spec;
    spec.length_mm = length_mm;
    spec.elements = static_cast<std::size_t>(std::lround(length_mm / 10.0));
    spec.radius_mm = cf_q160l::kRadius_mm;
    spec.section = cf_q160l::section();
    return spec;
}

/// Sum of the contacts' normal forces [N] and the largest friction ratio |f_T| / f_n.
struct WallLoad {
    double normal_N = 0;
    double axial_friction_N = 0;
};
WallLoad wall_load(const World& world) {
    WallLoad load;
    for (const WorldContact& c : world.contacts()) {
        load.normal_N += c.normal_force_N;
        load.axial_friction_N += c.force_N.x();
    }
    return load;
}

/// A 300 mm scope lying in a horizontal, clamped straight tube under gravity; the handle's depth is
/// held for 2 s (it settles on the wall), then the handle is pushed along the tube with
/// `push_ratio` x mu x (the wall's normal force) for 10 s. Returns the depth's drift speed [mm/s]
/// over the push (from its 2nd to its 10th second) and the wall's normal force [N].
struct PushOnWall {
    double drift_mm_per_s = 0;
    double depth_moved_mm = 0;
    double wall_normal_N = 0;
};
PushOnWall push_on_wall(double push_ratio, double mu) {
    const ColonTube tube =
        straight_tube(600.0, 15.0, ColonRegion::descending, cf_q160l::kRadius_mm);
    WorldSettings settings;
    settings.initial_insertion_mm = 300.0;
    settings.contact.friction_coefficient = mu;
    World world(scope_of(400.0), tube, default_colon_properties(), settings);
    HandleCommand command;
    command.insertion_mm = settings.initial_insertion_mm;
    const double h = settings.time_step_s;
    for (int i = 0; i < static_cast<int>(std::lround(2.0 / h)); ++i)
        EXPECT_TRUE(world.step(command).ok);
    PushOnWall out;
    out.wall_normal_N = wall_load(world).normal_N;
    command.force_controlled = true;
    command.push_force_N = push_ratio * mu * out.wall_normal_N;
    const double depth_start = world.insertion_depth_mm();
    double depth_at_2s = depth_start;
    const int steps = static_cast<int>(std::lround(10.0 / h));
    for (int i = 1; i <= steps; ++i) {
        EXPECT_TRUE(world.step(command).ok);
        if (i == static_cast<int>(std::lround(2.0 / h))) depth_at_2s = world.insertion_depth_mm();
    }
    out.depth_moved_mm = world.insertion_depth_mm() - depth_start;
    out.drift_mm_per_s = (world.insertion_depth_mm() - depth_at_2s) / 8.0;
    return out;
}

TEST(StaticFriction, AScopePushedBelowCoulombsLimitDoesNotMove) {
    // mu = 0.3: the push is 60 % of the static limit mu * N.
    const PushOnWall r = push_on_wall(0.6, 0.3);
    EXPECT_GT(r.wall_normal_N, 0.5);  // the wall carries most of the 400 mm scope's weight
    EXPECT_LE(std::abs(r.drift_mm_per_s), 1e-3) << "moved " << r.depth_moved_mm << " mm in 10 s";
}

TEST(StaticFriction, AScopePushedAboveCoulombsLimitSlides) {
    // 150 % of mu * N: Coulomb's dynamic limit cannot hold it; it accelerates along the tube.
    const PushOnWall r = push_on_wall(1.5, 0.3);
    EXPECT_GT(r.depth_moved_mm, 50.0) << "drift " << r.drift_mm_per_s << " mm/s";
}

/// Pushes a 600 mm scope at 20 mm/s through a 115 degree clamped bend (mu = 0.3) until the tip is
/// 130 mm past it, rests 0.5 s, withdraws 25 mm at 20 mm/s (the scope crosses from the bend's
/// outer wall to its inner one and every contact slides), then 20 mm more at `speed_mm_per_s`;
/// time step `h_s`. Returns the mean handle force [N] over the last 20 mm: two node spacings,
/// so that the ripple of nodes entering and leaving the bend averages out.
double pull_force_through_bend(double h_s, double speed_mm_per_s) {
    const ColonTube tube =
        single_bend(150.0, 40.0, 2.0, 15.0, ColonRegion::descending, cf_q160l::kRadius_mm);
    WorldSettings settings;
    settings.time_step_s = h_s;
    settings.gravity_mm_per_s2.setZero();
    settings.initial_insertion_mm = 50.0;
    settings.contact.friction_coefficient = 0.3;
    World world(scope_of(600.0), tube, default_colon_properties(), settings);
    HandleCommand command;
    command.insertion_mm = settings.initial_insertion_mm;
    double force_sum_N = 0.0;
    int samples = 0;
    auto run_to = [&](double depth_mm, double speed, bool sample) {
        const double step_mm = speed * h_s;
        while (std::abs(command.insertion_mm - depth_mm) > 1e-9) {
            const double left = depth_mm - command.insertion_mm;
            command.insertion_mm += std::abs(left) < step_mm ? left : std::copysign(step_mm, left);
            EXPECT_TRUE(world.step(command).ok);
            if (sample) {
                force_sum_N += world.handle_force_N();
                ++samples;
            }
        }
    };
    run_to(330.0, 20.0, false);
    for (int i = 0; i < static_cast<int>(std::lround(0.5 / h_s)); ++i)
        EXPECT_TRUE(world.step(command).ok);
    run_to(305.0, 20.0, false);
    run_to(295.0, speed_mm_per_s, false);
    run_to(275.0, speed_mm_per_s, true);
    return force_sum_N / samples;
}

TEST(StaticFriction, SlowPullsThroughABendFeelTheSameForceAtEveryTimeStep) {
    const double f10 = pull_force_through_bend(0.010, 5.0);
    const double f5 = pull_force_through_bend(0.005, 5.0);
    const double f2 = pull_force_through_bend(0.002, 5.0);
    // A pull: the wall's friction resists the withdrawal. The scope's bending presses it on the
    // bend's walls with ~17 N in all, so Coulomb's mu = 0.3 gives a few newtons.
    EXPECT_LT(f2, -2.0);
    EXPECT_NEAR(f5 / f2, 1.0, 0.03) << f2 << " N at 2 ms, " << f5 << " N at 5 ms";
    EXPECT_NEAR(f10 / f2, 1.0, 0.03) << f2 << " N at 2 ms, " << f10 << " N at 10 ms";
}

TEST(StaticFriction, SlowPullsThroughABendFeelTheSameForceAtEverySpeed) {
    const double v2 = pull_force_through_bend(0.005, 2.0);
    const double v5 = pull_force_through_bend(0.005, 5.0);
    const double v20 = pull_force_through_bend(0.005, 20.0);
    EXPECT_NEAR(v5 / v2, 1.0, 0.03) << v2 << " N at 2 mm/s, " << v5 << " N at 5 mm/s";
    EXPECT_NEAR(v20 / v2, 1.0, 0.03) << v2 << " N at 2 mm/s, " << v20 << " N at 20 mm/s";
}

}  // namespace
}  // namespace scopekin::model
