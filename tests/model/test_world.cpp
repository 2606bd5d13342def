// The world's building blocks and contracts. Expected numbers are independent of the code under
// test: a dense inverse computed by Eigen, Timoshenko closed forms, and hand-made geometry.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "model/colon/bundled_colons.hpp"
#include "model/colon/colon_compliance.hpp"
#include "model/linalg/selected_inverse.hpp"
#include "model/model_error.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/verification/contact_verification.hpp"
#include "model/world/world.hpp"

namespace scopekin::model {
namespace {

TEST(SelectedInverse, MatchesDenseInverseOfNonSymmetricMatrix) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const std::size_t n = 12;
    BlockTridiagonalMatrix a(n);
    for (std::size_t i = 0; i < n; ++i) {
        a.diagonal(i) = Mat6::NullaryExpr([&] { return u(rng); }) + 8.0 * Mat6::Identity();
        if (i + 1 < n) {
            a.upper(i) = Mat6::NullaryExpr([&] { return u(rng); });
            a.lower(i) = Mat6::NullaryExpr([&] { return u(rng); });
        }
    }
    const Eigen::MatrixXd dense_inverse = a.to_dense().inverse();
    const std::vector<std::size_t> nodes{1, 4, 5, 11};
    Eigen::MatrixXd blocks;
    SelectedInverse selected;
    ASSERT_TRUE(selected.translational_blocks(a, nodes, blocks));
    for (std::size_t p = 0; p < nodes.size(); ++p)
        for (std::size_t q = 0; q < nodes.size(); ++q) {
            const Eigen::Matrix3d expected = dense_inverse.block<3, 3>(
                static_cast<Eigen::Index>(6 * nodes[p]), static_cast<Eigen::Index>(6 * nodes[q]));
            const Eigen::Matrix3d got = blocks.block<3, 3>(static_cast<Eigen::Index>(3 * p),
                                                           static_cast<Eigen::Index>(3 * q));
            EXPECT_LT((got - expected).norm(), 1e-12) << "block " << p << "," << q;
        }
}

TEST(SelectedInverse, RejectsUnsortedNodes) {
    BlockTridiagonalMatrix a(3);
    for (std::size_t i = 0; i < 3; ++i)
        a.diagonal(i) = Mat6::Identity();
    Eigen::MatrixXd blocks;
    SelectedInverse selected;
    EXPECT_THROW(selected.translational_blocks(a, {2, 1}, blocks), ModelError);
}

// A colon stretch with its ends held and no mesentery is a clamped-clamped hollow Timoshenko
// beam: midspan deflection under P is P L^3 / (192 E I) + P L / (4 kappa G A).
TEST(ColonCompliance, ClampedTubeMatchesTimoshenkoClosedForm) {
    const double length = 200.0, radius = 15.0, wall = 2.0, e_kPa = 360.0;
    const ColonTube tube = straight_tube(length, radius, ColonRegion::sigmoid, 6.65);
    auto properties = default_colon_properties();
    auto& sigmoid = properties[static_cast<std::size_t>(ColonRegion::sigmoid)];
    sigmoid.mesentery_stiffness_N_per_mm2 = 0.0;
    sigmoid.young_modulus_kPa = e_kPa;
    sigmoid.wall_thickness_mm = wall;
    const ColonCompliance compliance(build_colon_structure(tube, properties));
    const double e = e_kPa * 1e-3, ro = radius + wall;
    const double i = M_PI / 4.0 * (std::pow(ro, 4) - std::pow(radius, 4));
    const double area = M_PI * (ro * ro - radius * radius);
    const double kappa_g_a = 0.5 * e / (2.0 * 1.49) * area;
    const double expected =
        std::pow(length, 3) / (192.0 * e * i) + length / (4.0 * kappa_g_a);  // mm/N
    const std::size_t mid = tube.point_count() / 2;
    ASSERT_NEAR(tube.points()[mid].position_mm.x(), length / 2.0, 1e-9);
    EXPECT_NEAR(compliance.node_block(mid, mid)(1, 1), expected, 1e-9 * expected);
    EXPECT_NEAR(compliance.node_block(mid, mid)(2, 2), expected, 1e-9 * expected);
    EXPECT_EQ(compliance.node_block(0, 0).norm(), 0.0);  // the clamped end does not move
}

TEST(ColonCompliance, MobileStretchIsHeldByItsClampedEnds) {
    // The ends of a colon always stay with a fixed neighbour (build_colon_structure), so even an
    // all-mesentery tube with zero mesentery stiffness is held and its compliance finite.
    const ColonTube tube = straight_tube(100.0, 15.0, ColonRegion::sigmoid, 6.65);
    auto properties = default_colon_properties();
    properties[static_cast<std::size_t>(ColonRegion::sigmoid)].mesentery_stiffness_N_per_mm2 = 0.0;
    EXPECT_NO_THROW(ColonCompliance(build_colon_structure(tube, properties)));
}

ScopeSpec short_scope() {
    ScopeSpec spec;
    spec.length_mm = 400.0;
    spec.elements = 40;
    spec.radius_mm = cf_q160l::kRadius_mm;
    spec.section = cf_q160l::section();
    return spec;
}

TEST(World, InitialInsertionThroughTheWallIsRejected) {
    // The bend starts 100 mm in: 250 mm of straight scope would pass through its wall.
    const ColonTube tube =
        single_bend(100.0, 30.0, 1.5, 15.0, ColonRegion::sigmoid, cf_q160l::kRadius_mm);
    WorldSettings settings;
    settings.initial_insertion_mm = 250.0;
    try {
        World world(short_scope(), tube, default_colon_properties(), settings);
        FAIL() << "accepted";
    } catch (const ModelError& e) {
        EXPECT_NE(std::string(e.what()).find("initial_insertion_mm"), std::string::npos)
            << e.what();
    }
}

TEST(World, BadSettingsNameTheField) {
    const ColonTube tube =
        straight_tube(300.0, 15.0, ColonRegion::descending, cf_q160l::kRadius_mm);
    WorldSettings settings;
    settings.contact.friction_coefficient = -0.1;
    EXPECT_THROW(World(short_scope(), tube, default_colon_properties(), settings), ModelError);
    settings = WorldSettings{};
    settings.time_step_s = 0.1;
    EXPECT_THROW(World(short_scope(), tube, default_colon_properties(), settings), ModelError);
    settings = WorldSettings{};
    settings.contact.relaxation = 2.0;
    EXPECT_THROW(World(short_scope(), tube, default_colon_properties(), settings), ModelError);
}

TEST(World, FailedStepLeavesTheWorldUnchanged) {
    const ColonTube tube =
        straight_tube(300.0, 15.0, ColonRegion::descending, cf_q160l::kRadius_mm);
    World world(short_scope(), tube, default_colon_properties(), WorldSettings{});
    const Eigen::Vector3d tip = world.node_position_mm(world.scope_node_count() - 1);
    HandleCommand bad;
    bad.insertion_mm = std::nan("");
    const WorldStepReport r = world.step(bad);
    EXPECT_FALSE(r.ok);
    EXPECT_FALSE(r.failure.empty());
    EXPECT_EQ(world.time_s(), 0.0);
    EXPECT_EQ((world.node_position_mm(world.scope_node_count() - 1) - tip).norm(), 0.0);
}

// A world restored from another's state continues exactly as the other (the same arithmetic
// from the same numbers), and a state of another scope is refused.
TEST(World, RestoredStateContinuesBitIdentically) {
    const ColonTube tube =
        single_bend(120.0, 40.0, 1.2, 15.0, ColonRegion::sigmoid, cf_q160l::kRadius_mm);
    WorldSettings settings;
    settings.initial_insertion_mm = 60.0;
    World first(short_scope(), tube, default_colon_properties(), settings);
    HandleCommand push;
    auto command_at = [&](int k) {
        push.insertion_mm = 60.0 + 0.8 * k;
        push.roll_rad = 0.002 * k;
        return push;
    };
    for (int k = 1; k <= 120; ++k)
        ASSERT_TRUE(first.step(command_at(k)).ok);
    ASSERT_GT(first.contacts().size(), 0U);
    const World::State saved = first.state();
    World second(short_scope(), tube, default_colon_properties(), settings);
    second.restore(saved);
    EXPECT_EQ(second.time_s(), first.time_s());
    for (int k = 121; k <= 200; ++k) {
        ASSERT_TRUE(first.step(command_at(k)).ok);
        ASSERT_TRUE(second.step(command_at(k)).ok);
    }
    EXPECT_EQ(second.time_s(), first.time_s());
    EXPECT_EQ(second.handle_force_N(), first.handle_force_N());
    for (std::size_t n = 0; n < first.scope_node_count(); ++n)
        EXPECT_EQ((second.node_position_mm(n) - first.node_position_mm(n)).norm(), 0.0)
            << "node " << n;
    ASSERT_EQ(second.contacts().size(), first.contacts().size());
    // The colon's one-node position is the all-nodes one (a sum in another order: to rounding).
    const std::vector<Eigen::Vector3d> colon = first.colon_positions_mm();
    double moved = 0.0;
    for (std::size_t i = 0; i < colon.size(); ++i) {
        EXPECT_LT((first.colon_position_mm(i) - colon[i]).norm(), 1e-9) << "colon node " << i;
        moved = std::max(moved, (colon[i] - tube.points()[i].position_mm).norm());
    }
    EXPECT_GT(moved, 1e-3);  // the check means something: the wall is pushed
    EXPECT_THROW((void)first.colon_position_mm(colon.size()), ModelError);

    ScopeSpec longer = short_scope();
    longer.elements += 2;
    World other(longer, tube, default_colon_properties(), settings);
    EXPECT_THROW(other.restore(saved), ModelError);
}

TEST(World, HeldScopeRestsOnTheTubeAndTheWallCarriesItsWeight) {
    // A scope 150 mm into a rigid straight tube under gravity (-z), handle held: after settling,
    // the wall's vertical forces plus the hand's carry the inserted weight; the wall's share is at
    // most the weight of the inserted part (w l = 4/350 N/mm x 150 mm = 1.71 N).
    const ColonTube tube =
        straight_tube(400.0, 15.0, ColonRegion::descending, cf_q160l::kRadius_mm);
    WorldSettings settings;
    settings.initial_insertion_mm = 150.0;
    World world(short_scope(), tube, default_colon_properties(), settings);
    HandleCommand hold;
    hold.insertion_mm = 150.0;
    for (int i = 0; i < 150; ++i)
        ASSERT_TRUE(world.step(hold).ok);
    double vertical = 0.0;
    for (const WorldContact& c : world.contacts())
        vertical += c.normal_force_N * c.normal.z();
    const double inserted_weight = cf_q160l::kWeightPerLength_N_per_mm * 150.0;
    EXPECT_GT(vertical, 0.2 * inserted_weight);
    EXPECT_LE(vertical, inserted_weight * 1.001);
    for (const WorldContact& c : world.contacts())
        EXPECT_GT(c.normal.z(), 0.9);  // wall below pushes up
}

// A node found in the wall at a step's start (in a run: a contact released the step before and
// the massless colon sprang back under it) leaves it at 100 mm/s, 1 mm per 10 ms step, instead of
// being thrown out in one step: thrown at depth / h, it crossed the lumen, and the contact forces
// alternated from step to step (model/world/world.cpp, kMaxDepenetration_mm_per_s).
TEST(World, ANodeFoundInTheWallLeavesItAtTheDepenetrationSpeed) {
    // 150 mm of scope settled on the floor of a straight rigid tube; then the tube's centerline is
    // raised by 4 mm beyond 100 mm (a 50 mm ramp before): the nodes there begin 4 mm in its floor.
    const ColonTube flat =
        straight_tube(400.0, 15.0, ColonRegion::descending, cf_q160l::kRadius_mm);
    WorldSettings settings;
    settings.initial_insertion_mm = 150.0;
    World settled(short_scope(), flat, default_colon_properties(), settings);
    HandleCommand hold;
    hold.insertion_mm = 150.0;
    for (int i = 0; i < 150; ++i)
        ASSERT_TRUE(settled.step(hold).ok);
    constexpr double kRaise_mm = 4.0;
    std::vector<ColonPoint> points = flat.points();
    for (ColonPoint& p : points)
        p.position_mm.z() += kRaise_mm * std::clamp((p.position_mm.x() - 50.0) / 50.0, 0.0, 1.0);
    const ColonTube raised("raised_floor", std::move(points), cf_q160l::kRadius_mm);
    World world(short_scope(), raised, default_colon_properties(), settings);
    World::State state = settled.state();
    // The state carries the colon's rest shape (it may have pleated): the raised one, then. The
    // tube runs along the entry axis, so its frame is the computation frame.
    ASSERT_EQ(state.telescoping.position_mm.size(), raised.point_count());
    for (std::size_t i = 0; i < raised.point_count(); ++i) {
        state.telescoping.position_mm[i] = raised.points()[i].position_mm;
        state.pleated_tube_mm[i] = raised.points()[i].position_mm;
    }
    world.restore(state);
    auto deepest_mm = [&] {
        double gap = 0.0;
        for (const WorldContact& c : world.contacts())
            gap = std::min(gap, c.gap_mm);
        return -gap;
    };
    const double out_per_step_mm = 100.0 * settings.time_step_s;  // 1 mm
    for (int k = 1; k <= 3; ++k) {
        ASSERT_TRUE(world.step(hold).ok);
        // (to 0.15 mm: the scope unbends a little as it leaves the ramp)
        EXPECT_NEAR(deepest_mm(), kRaise_mm - k * out_per_step_mm, 0.15) << "step " << k;
    }
    for (int k = 4; k <= 10; ++k)
        ASSERT_TRUE(world.step(hold).ok);
    EXPECT_LT(deepest_mm(), 0.05);
    double fastest_mm_per_s = 0.0;
    for (std::size_t n = 0; n < world.scope_node_count(); ++n)
        fastest_mm_per_s = std::max(fastest_mm_per_s, world.node_velocity_mm_per_s(n).norm());
    EXPECT_LT(fastest_mm_per_s, 110.0);  // out of the wall, and not thrown on across the lumen
}

TEST(World, FrictionOnlyDissipatesAndNothingPenetratesInTheBend) {
    const auto r = contact_verification::push_through_tube(2.0, 0.25, 5.0, 1.0);
    ASSERT_TRUE(r.ok) << r.failure;
    EXPECT_LE(r.max_friction_work_Nmm, 1e-5);
    EXPECT_LE(r.max_penetration_mm, 1e-4);
    EXPECT_GT(r.loaded_contacts_in_bend, 0U);
    EXPECT_EQ(r.loaded_contacts_on_outer_wall, r.loaded_contacts_in_bend);
}

TEST(World, SelfLockingAboveTheFrictionAngleSlidingBelow) {
    // The push ends at 4.5 s, before the stuck scope buckles into step-size dependent loops (see
    // contact_verification::world_rows).
    const auto locked = contact_verification::push_through_tube(2.0, 1.2, 4.5, 1.5);
    const auto sliding = contact_verification::push_through_tube(2.0, 0.05, 4.5, 1.5);
    ASSERT_TRUE(locked.ok && sliding.ok) << locked.failure << sliding.failure;
    EXPECT_TRUE(locked.tip_sticking);
    EXPECT_LT(locked.tip_driving_angle_rad, std::atan(1.2));  // alpha < beta: stick (thesis 2.2.1)
    EXPECT_LT(locked.tip_sliding_mm, 0.02 * locked.handle_advance_mm);
    EXPECT_GT(sliding.tip_sliding_mm, 0.7 * sliding.handle_advance_mm);
    EXPECT_NEAR(sliding.tip_driving_angle_rad, std::atan(0.05), 1e-6);  // slipping on the cone
    EXPECT_GT(locked.handle_force_N, 5.0 * sliding.handle_force_N);  // pushing harder for nothing
}

TEST(World, FrictionZonesAndEffectsSetTheCoefficientPerContact) {
    struct DoubleFriction : WorldEffect {
        std::string name() const override { return "double_friction_in_sigmoid"; }
        double friction_coefficient(double, ColonRegion region, double mu) const override {
            return region == ColonRegion::sigmoid ? 2.0 * mu : mu;
        }
    };
    const ColonTube tube =
        single_bend(100.0, 40.0, 2.0, 15.0, ColonRegion::sigmoid, cf_q160l::kRadius_mm);
    WorldSettings settings;
    settings.gravity_mm_per_s2.setZero();
    settings.initial_insertion_mm = 50.0;
    settings.contact.friction_coefficient = 0.1;
    settings.contact.friction_zones = {{0.0, 25.0, 0.2}};  // the distal 25 mm
    World world(short_scope(), tube, default_colon_properties(), settings,
                {std::make_shared<DoubleFriction>()});
    HandleCommand c;
    bool seen_tip = false, seen_shaft = false;
    for (int i = 0; i < 500; ++i) {
        c.insertion_mm = 50.0 + 0.5 * (i + 1);
        ASSERT_TRUE(world.step(c).ok);
        for (const WorldContact& k : world.contacts()) {
            if (k.arc_from_tip_mm < 25.0) {
                EXPECT_DOUBLE_EQ(k.friction_coefficient, 0.4);
                seen_tip = true;
            } else {
                EXPECT_DOUBLE_EQ(k.friction_coefficient, 0.2);
                seen_shaft = true;
            }
        }
    }
    EXPECT_TRUE(seen_tip && seen_shaft);
}

}  // namespace
}  // namespace scopekin::model
