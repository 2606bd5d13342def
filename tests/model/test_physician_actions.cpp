// What the physician and the assistant do besides moving the handle (model/scenario/): the
// physician's tip steering and the assistant's abdominal pressure. Expected numbers are hand
// computations on hand-built geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "model/colon/bundled_colons.hpp"
#include "model/model_error.hpp"
#include "model/scenario/abdominal_pressure.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"
#include "model/scenario/tip_steering.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model_test_support.hpp"

namespace scopekin::model {
namespace {

const double kScopeRadius = cf_q160l::kRadius_mm;

TEST(AbdominalPressure, PressesBowingNodesBackInsideItsWindowAndRegions) {
    const ColonTube sigmoid = straight_tube(400.0, 15.0, ColonRegion::sigmoid, kScopeRadius);
    const double free_play = 15.0 - kScopeRadius;  // 8.35 mm: the node touches the rest wall there
    AbdominalPressureWindow w;
    w.start_s = 10.0;
    w.end_s = 20.0;
    w.regions = {ColonRegion::sigmoid, ColonRegion::transverse};
    w.stiffness_N_per_mm2 = 0.07;
    w.ramp_s = 2.0;
    const AbdominalPressure pressure({w});

    // Pressed in fully (t >= start + ramp): F = -k l excess u. Node 0 carries 5 mm of scope (half
    // an element at the end), node 1 10 mm; the tip is inside the lumen.
    std::vector<NodalLoad> loads;
    pressure.add_scope_loads(testing::three_node_view(sigmoid, 15.0), loads);
    ASSERT_EQ(loads.size(), 2u);
    EXPECT_EQ(loads[0].node, 0u);
    EXPECT_LT(
        (loads[0].force_N - Eigen::Vector3d(0.0, -0.07 * 5.0 * (12.0 - free_play), 0.0)).norm(),
        1e-13);
    EXPECT_EQ(loads[1].node, 1u);
    EXPECT_NEAR(loads[1].force_N.z(), -8.155, 1e-12);  // 0.07 x 10 x 11.65
    EXPECT_EQ(loads[1].moment_Nmm.norm(), 0.0);

    // Half-way through the ramp: half the force.
    loads.clear();
    pressure.add_scope_loads(testing::three_node_view(sigmoid, 11.0), loads);
    ASSERT_EQ(loads.size(), 2u);
    EXPECT_NEAR(loads[1].force_N.z(), -8.155 / 2.0, 1e-12);

    // Outside the window (before, at the end: windows are [start, end)): nothing.
    for (double t : {9.99, 20.0}) {
        loads.clear();
        pressure.add_scope_loads(testing::three_node_view(sigmoid, t), loads);
        EXPECT_TRUE(loads.empty()) << t;
    }
    // A region the hand does not press: nothing.
    const ColonTube descending = straight_tube(400.0, 15.0, ColonRegion::descending, kScopeRadius);
    loads.clear();
    pressure.add_scope_loads(testing::three_node_view(descending, 15.0), loads);
    EXPECT_TRUE(loads.empty());
    // Held nodes (outside the body) are the hand's.
    WorldEffectView held = testing::three_node_view(sigmoid, 15.0);
    held.scope_node_held = {true, true, false};
    loads.clear();
    pressure.add_scope_loads(held, loads);
    EXPECT_TRUE(loads.empty());
}

TEST(AbdominalPressure, BadWindowsAreRefusedNamingTheField) {
    auto expect_error = [](AbdominalPressureWindow w, const std::string& fragment) {
        try {
            AbdominalPressure pressure({w});
            ADD_FAILURE() << "accepted; expected " << fragment;
        } catch (const ModelError& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        }
    };
    AbdominalPressureWindow w;
    w.start_s = 1.0;
    w.end_s = 2.0;
    AbdominalPressureWindow bad = w;
    bad.end_s = 1.0;
    expect_error(bad, "abdominal_pressure[0].end_s");
    bad = w;
    bad.regions.clear();
    expect_error(bad, "abdominal_pressure[0].regions");
    bad = w;
    bad.stiffness_N_per_mm2 = 0.0;
    expect_error(bad, "abdominal_pressure[0].stiffness_N_per_mm2");
    bad = w;
    bad.ramp_s = 1.5;  // longer than the window
    expect_error(bad, "abdominal_pressure[0].ramp_s");
}

/// Twelve nodes 10 mm apart on the axis of a straight tube along +x, the tip node lifted by
/// `lift_mm` along +z: the tip's axis makes atan(lift / 10) with the lumen ahead.
WorldEffectView straight_scope_with_tilted_tip(const ColonTube& tube, double lift_mm) {
    WorldEffectView v;
    v.time_s = 1.0;
    v.time_step_s = 0.01;
    v.insertion_depth_mm = 120.0;
    v.scope_radius_mm = kScopeRadius;
    for (int i = 0; i < 12; ++i) {
        v.scope_nodes_mm.emplace_back(10.0 + 10.0 * i, 0.0, i == 11 ? lift_mm : 0.0);
        v.arc_from_tip_mm.push_back(10.0 * (11 - i));
    }
    v.scope_velocities_mm_per_s.assign(12, Eigen::Vector3d::Zero());
    v.scope_axes.assign(12, Eigen::Vector3d::UnitX());
    v.scope_node_held.assign(12, false);
    v.colon_at_rest = &tube;
    return v;
}

TEST(TipSteering, CoupleBendsTheSectionTowardsTheLumenAhead) {
    const ColonTube tube = straight_tube(400.0, 15.0, ColonRegion::sigmoid, kScopeRadius);
    const double ei_Nmm2 = 1.0e6;
    SteeringWindow window;
    window.start_s = 0.0;
    window.end_s = 5.0;
    window.lookahead_mm = 40.0;
    window.bending_section_mm = 80.0;
    window.gain = 0.5;
    const TipSteering steering({window}, tube, ei_Nmm2, 10.0);
    std::vector<NodalLoad> loads;
    steering.add_scope_loads(straight_scope_with_tilted_tip(tube, 2.0), loads);
    // The tip (120, 0, 2) points along (10, 0, 2); the lumen 40 mm ahead is the centerline point
    // at 160 mm: direction (40, 0, -2). theta = atan(2/10) + atan(2/40); the couple's axis is
    // a x d = (0, 100, 0) / 100 = +y; M = gain EI theta / L_bend, at the tip and (opposite) 8 elements behind it.
    const double theta = std::atan(0.2) + std::atan(0.05);
    const double moment = 0.5 * ei_Nmm2 * theta / 80.0;
    ASSERT_EQ(loads.size(), 2u);
    EXPECT_EQ(loads[0].node, 11u);
    EXPECT_EQ(loads[1].node, 3u);
    EXPECT_LT((loads[0].moment_Nmm - Eigen::Vector3d(0.0, moment, 0.0)).norm(), 1e-6 * moment)
        << loads[0].moment_Nmm.transpose();
    EXPECT_LT((loads[1].moment_Nmm + loads[0].moment_Nmm).norm(), 1e-9);
    EXPECT_EQ(loads[0].force_N.norm() + loads[1].force_N.norm(), 0.0);

    // A tip that points down the lumen is left alone; so is any tip outside the window.
    loads.clear();
    const TipSteering fresh({window}, tube, ei_Nmm2, 10.0);
    fresh.add_scope_loads(straight_scope_with_tilted_tip(tube, 0.0), loads);
    EXPECT_TRUE(loads.empty());
    WorldEffectView late = straight_scope_with_tilted_tip(tube, 2.0);
    late.time_s = 5.0;
    loads.clear();
    steering.add_scope_loads(late, loads);
    EXPECT_TRUE(loads.empty());
}

TEST(TipSteering, FollowingTheTurnBendsFurtherIntoAFlexure) {
    // A straight scope whose tip (120, 0, 0) points along +x into a 90 degree bend of radius
    // 40 mm turning towards +y. Aimed at the point 40 mm ahead, the section bends by the angle
    // between the tip's axis and the direction to that point (about half the turn so far: the
    // chord); following the turn, by the angle to the mean of that direction and the
    // centerline's own direction there (about three quarters of it). Both about +z.
    const ColonTube tube =
        single_bend(120.0, 40.0, M_PI / 2.0, 15.0, ColonRegion::sigmoid, kScopeRadius);
    const double ei_Nmm2 = 1.0e6;
    SteeringWindow window;
    window.start_s = 0.0;
    window.end_s = 5.0;
    window.gain = 1.0;
    WorldEffectView view = straight_scope_with_tilted_tip(tube, 0.0);
    // The centerline point the law aims at: the first at or past the tip's place + 40 mm.
    std::size_t j = 0;
    while (tube.arc_length_mm(j) < 120.0 + window.lookahead_mm)
        ++j;
    const Eigen::Vector3d tip(120.0, 0.0, 0.0), axis = Eigen::Vector3d::UnitX();
    const Eigen::Vector3d d = (tube.points()[j].position_mm - tip).normalized();
    const Eigen::Vector3d t =
        (tube.points()[j + 1].position_mm - tube.points()[j].position_mm).normalized();
    const double theta_point = std::acos(axis.dot(d));
    const double theta_turn = std::acos(axis.dot((d + t).normalized()));
    for (bool follows : {false, true}) {
        SCOPED_TRACE(follows ? "follows the turn" : "aims at the point");
        window.follows_turn = follows;
        const TipSteering steering({window}, tube, ei_Nmm2, 10.0);
        std::vector<NodalLoad> loads;
        steering.add_scope_loads(view, loads);
        ASSERT_EQ(loads.size(), 2u);
        const double theta = follows ? theta_turn : theta_point;
        const Eigen::Vector3d expected(0.0, 0.0, ei_Nmm2 * theta / window.bending_section_mm);
        EXPECT_LT((loads[0].moment_Nmm - expected).norm(), 1e-6 * expected.norm())
            << loads[0].moment_Nmm.transpose();
    }
    // The chord to the point 40 mm along the arc turns by half its angle (1 rad); the turn's own
    // direction there by the whole: the point-aimed angle is about 0.5 rad, the turn-following
    // one between the two.
    EXPECT_NEAR(theta_point, 0.5, 0.1);
    EXPECT_GT(theta_turn, theta_point + 0.15);
    EXPECT_LT(theta_turn, 1.0 + 0.1);
}

nlohmann::json scenario_with_pressure() {
    return nlohmann::json::parse(R"({
    "colon": {"bundled": "single_bend", "lead_mm": 100, "bend_radius_mm": 40, "bend_angle_deg": 115,
              "inner_radius_mm": 15},
    "scope": {"model": "cf_q160l", "length_mm": 300, "elements": 30},
    "initial_insertion_mm": 40,
    "procedure": [{"action": "advance", "start_s": 0, "end_s": 0.3, "speed_mm_per_s": 50}],
    "abdominal_pressure": [{"start_s": 0.1, "end_s": 0.3, "regions": ["sigmoid", "transverse"],
                            "stiffness_N_per_mm2": 0.05, "ramp_s": 0.1}]
  })");
}

TEST(AbdominalPressure, ReadFromTheScenarioAndRun) {
    const Scenario s = read_scenario(scenario_with_pressure(), "s.json");
    ASSERT_EQ(s.abdominal_pressure.size(), 1u);
    EXPECT_EQ(s.abdominal_pressure[0].regions,
              (std::vector<ColonRegion>{ColonRegion::sigmoid, ColonRegion::transverse}));
    EXPECT_EQ(s.abdominal_pressure[0].stiffness_N_per_mm2, 0.05);
    EXPECT_EQ(s.abdominal_pressure[0].ramp_s, 0.1);
    ASSERT_EQ(s.effects.size(), 1u);
    EXPECT_EQ(s.effects[0]->name(), "abdominal_pressure");
    auto world = build_world(s);
    const SimulationSummary sum = run_simulation(*world, s, {});
    EXPECT_TRUE(sum.complete) << sum.message;

    nlohmann::json doc = scenario_with_pressure();
    doc["abdominal_pressure"][0].erase("regions");
    doc["abdominal_pressure"][0].erase("ramp_s");
    const Scenario defaults = read_scenario(doc, "s.json");
    EXPECT_EQ(defaults.abdominal_pressure[0].regions,
              std::vector<ColonRegion>{ColonRegion::sigmoid});
    EXPECT_DOUBLE_EQ(defaults.abdominal_pressure[0].ramp_s, 0.2);  // 1 s, but at most the window
}

TEST(AbdominalPressure, BadScenarioKeysNameTheirPath) {
    auto expect = [](const nlohmann::json& doc, const std::string& fragment) {
        try {
            read_scenario(doc, "s.json");
            ADD_FAILURE() << "accepted; expected " << fragment;
        } catch (const ModelError& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        }
    };
    nlohmann::json doc = scenario_with_pressure();
    doc["abdominal_pressure"][0]["regions"] = {"sigmoid", "spleen"};
    expect(doc, "s.json: abdominal_pressure[0].regions[1]: unknown region 'spleen'");
    doc = scenario_with_pressure();
    doc["abdominal_pressure"][0]["regions"] = nlohmann::json::array();
    expect(doc, "s.json: abdominal_pressure[0].regions: name at least one region");
    doc = scenario_with_pressure();
    doc["abdominal_pressure"][0]["hand"] = "left";
    expect(doc, "s.json: abdominal_pressure[0].hand: unknown key");
    doc = scenario_with_pressure();
    doc["abdominal_pressure"][0]["stiffness_N_per_mm2"] = 2;
    expect(doc, "s.json: abdominal_pressure[0].stiffness_N_per_mm2: 2 must be in (0, 1]");
    doc = scenario_with_pressure();
    doc["abdominal_pressure"][0]["ramp_s"] = 0.5;
    expect(doc, "s.json: abdominal_pressure[0].ramp_s: 0.5 s must be in [0, end_s - start_s]");
    doc = scenario_with_pressure();
    doc["abdominal_pressure"][0]["end_s"] = 0.1;
    expect(doc, "s.json: abdominal_pressure[0].end_s: 0.1 s must be later than start_s");
}

}  // namespace
}  // namespace scopekin::model
