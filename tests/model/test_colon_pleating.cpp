// Telescoping (model/colon/colon_pleating.hpp) on a made-up colon: 50 mm of fixed colon, a mobile
// half circle of radius 50 mm in 20 chords, 50 mm of fixed colon. Expected numbers are closed
// forms: the chord polygon's length 20 * 2R sin(pi/40), the law's equilibrium
// q* = (D - D_0) / (D - D_0 + D_h), the recoil's exponential, and lengths the shape must have.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "model/colon/colon_pleating.hpp"
#include "model/model_error.hpp"

namespace {
using namespace scopekin::model;

constexpr double kRadius_mm = 50.0;
constexpr int kChords = 20;

struct Colon {
    std::vector<Eigen::Vector3d> nodes;
    std::vector<bool> mobile;
};

Colon half_circle_colon() {
    Colon c;
    for (int i = 0; i <= 5; ++i)  // fixed lead along +x towards the loop, 10 mm apart
        c.nodes.emplace_back(-50.0 + 10.0 * i, 0.0, 0.0);
    for (int i = 1; i <= kChords; ++i) {  // the loop: from (0,0,0) to (100,0,0) over +y
        const double a = M_PI * (1.0 - static_cast<double>(i) / kChords);
        c.nodes.emplace_back(kRadius_mm + kRadius_mm * std::cos(a), kRadius_mm * std::sin(a), 0.0);
    }
    for (int i = 1; i <= 5; ++i)
        c.nodes.emplace_back(100.0, -10.0 * i, 0.0);  // fixed tail, -y
    c.mobile.assign(c.nodes.size(), false);
    for (int i = 6; i < 5 + kChords; ++i)  // nodes strictly inside the loop
        c.mobile[static_cast<std::size_t>(i)] = true;
    return c;
}

const double kLoopLength_mm = kChords * 2.0 * kRadius_mm * std::sin(M_PI / (2.0 * kChords));

/// `drag_N` towards the anus on the stretch, spread over its segments along their current
/// direction towards the anus (the scope dragging the stretch as it is withdrawn).
std::vector<ColonPointForce> drag_on_loop(const ColonPleating& pleating, double drag_N) {
    std::vector<ColonPointForce> forces;
    const auto& x = pleating.state().position_mm;
    for (std::size_t j = pleating.first_node(0) - 1; j <= pleating.last_node(0); ++j) {
        const Eigen::Vector3d towards_anus = (x[j] - x[j + 1]).normalized();
        forces.push_back({j, 0.5, drag_N / kChords * towards_anus});
    }
    return forces;
}

/// `seconds` of a constant `drag_N` towards the anus in steps of 10 ms.
void drag_for(ColonPleating& pleating, double drag_N, double seconds) {
    const auto steps = static_cast<int>(std::lround(seconds / 0.01));
    for (int n = 0; n < steps; ++n)
        pleating.advance(drag_on_loop(pleating, drag_N), 0.01);
}

/// The default law (D_0 1 N, D_h 2 N, tau 30 s), switched on (it is off unless asked for).
TelescopingLaw law() {
    TelescopingLaw l;
    l.enabled = true;
    return l;
}

TEST(ColonPleating, FindsTheStretchAndCapsItsPleatingByTheChord) {
    const Colon c = half_circle_colon();
    const ColonPleating pleating(c.nodes, c.mobile, law());
    ASSERT_EQ(pleating.stretch_count(), 1u);
    EXPECT_EQ(pleating.first_node(0), 6u);
    EXPECT_EQ(pleating.last_node(0), 24u);
    EXPECT_NEAR(pleating.rest_length_mm(0), kLoopLength_mm, 1e-9);
    // 1 - chord / length = 1 - 100 / 156.98 = 0.363; 90 % of it is below p_max = 0.6.
    EXPECT_NEAR(pleating.max_fraction(0), 0.9 * (1.0 - 100.0 / kLoopLength_mm), 1e-12);
}

TEST(ColonPleating, ShapeHasTheLengthOfItsFractionAndKeepsItsEnds) {
    const Colon c = half_circle_colon();
    ColonPleating pleating(c.nodes, c.mobile, law());
    for (double p : {0.1, 0.2, 0.3}) {
        pleating.solve_shape(0, p);
        EXPECT_NEAR(pleating.length_now_mm(0), (1.0 - p) * kLoopLength_mm, 1e-6) << p;
        EXPECT_EQ(pleating.state().position_mm[5], c.nodes[5]);
        EXPECT_EQ(pleating.state().position_mm[25], c.nodes[25]);
    }
    pleating.solve_shape(0, 0.0);
    for (std::size_t i = 0; i < c.nodes.size(); ++i)
        EXPECT_EQ(pleating.state().position_mm[i], c.nodes[i]) << i;
}

TEST(ColonPleating, ConstantDragSettlesWhereItMeetsTheResistance) {
    // D = 4 N: q* = (4 - 1) / (4 - 1 + 2) = 0.6 of p_max.
    const Colon c = half_circle_colon();
    ColonPleating pleating(c.nodes, c.mobile, law());
    drag_for(pleating, 4.0, 60.0);
    EXPECT_NEAR(pleating.state().fraction[0], 0.6 * pleating.max_fraction(0), 1e-4);
    EXPECT_NEAR(pleating.length_now_mm(0), (1.0 - pleating.state().fraction[0]) * kLoopLength_mm,
                1e-6);
    EXPECT_NEAR(pleating.drag_towards_anus_N(drag_on_loop(pleating, 4.0))[0], 4.0, 1e-9);
}

TEST(ColonPleating, BelowTheOnsetNothingPleats) {
    const Colon c = half_circle_colon();
    ColonPleating pleating(c.nodes, c.mobile, law());
    for (int n = 0; n < 1000; ++n)
        EXPECT_FALSE(pleating.advance(drag_on_loop(pleating, 0.9), 0.01));
    EXPECT_EQ(pleating.state().fraction[0], 0.0);
}

TEST(ColonPleating, TheScopeHoldsThePleatsWhilePushedTowardsTheCecum) {
    const Colon c = half_circle_colon();
    ColonPleating pleating(c.nodes, c.mobile, law());
    drag_for(pleating, 4.0, 20.0);
    const double held = pleating.state().fraction[0];
    ASSERT_GT(held, 0.1);
    drag_for(pleating, -5.0, 10.0);  // a 5 N push on towards the cecum
    EXPECT_EQ(pleating.state().fraction[0], held);
}

TEST(ColonPleating, AnUnloadedStretchRecoilsWithItsTimeConstant) {
    const Colon c = half_circle_colon();
    ColonPleating pleating(c.nodes, c.mobile, law());
    drag_for(pleating, 4.0, 20.0);
    const double p0 = pleating.state().fraction[0];
    for (int n = 0; n < 1000; ++n)  // 10 s, no contact
        pleating.advance({}, 0.01);
    EXPECT_NEAR(pleating.state().fraction[0] / p0, std::exp(-10.0 / 30.0), 2e-3);
}

TEST(ColonPleating, DisabledMovesNothing) {
    const Colon c = half_circle_colon();
    TelescopingLaw off = law();
    off.enabled = false;
    ColonPleating pleating(c.nodes, c.mobile, off);
    for (int n = 0; n < 100; ++n)
        EXPECT_FALSE(pleating.advance(drag_on_loop(pleating, 10.0), 0.01));
    EXPECT_EQ(pleating.state().position_mm, c.nodes);
}

TEST(ColonPleating, BadLawAndBadStateAreRefusedByName) {
    const Colon c = half_circle_colon();
    auto refused = [&](TelescopingLaw l, const std::string& field) {
        try {
            (void)ColonPleating(c.nodes, c.mobile, l);
            ADD_FAILURE() << field << " accepted";
        } catch (const ModelError& e) {
            EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
        }
    };
    TelescopingLaw l = law();
    l.max_fraction = 1.0;
    refused(l, "telescoping.max_fraction");
    l = law();
    l.onset_drag_N = -1.0;
    refused(l, "telescoping.onset_drag_N");
    l = law();
    l.recoil_time_s = 0.0;
    refused(l, "telescoping.recoil_time_s");
    ColonPleating pleating(c.nodes, c.mobile, law());
    ColonPleating::State other = pleating.state();
    other.fraction.push_back(0.0);
    EXPECT_THROW(pleating.restore(other), ModelError);
}

}  // namespace
