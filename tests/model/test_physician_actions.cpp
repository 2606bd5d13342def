// What the physician and the assistant do besides moving the handle (model/scenario/): the
// physician's tip steering and the assistant's abdominal pressure. Expected numbers are hand
// computations on hand-built geometry.
#include <gtest/gtest.h>

#include <algorithm>
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
    // Its stiffness k l u u^T (u = z here), for the world's step to take implicitly.
    Eigen::Matrix3d k_node = Eigen::Matrix3d::Zero();
    k_node(2, 2) = 0.07 * 10.0;
    EXPECT_LT((loads[1].stiffness_N_per_mm - k_node).norm(), 1e-13);

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

TEST(AbdominalPressure, APhysiciansAssistantGivesWayBeyondWhatAHandGives) {
    // The three-node view of the test above, pressed by a physician's assistant (SceneControl)
    // from t = 0, fully in at t = 15 s. Node 0 pushes the wall out by 3.65 mm over 5 mm of scope,
    // node 1 by 11.65 mm over 10 mm: at k = 1 N/mm per mm the spring asks 18.25 N along -y and
    // 116.5 N along -z, a net 117.92 N, beyond the hand's 50 N, so both forces and stiffnesses
    // shrink by 50 / 117.92.
    const ColonTube sigmoid = straight_tube(400.0, 15.0, ColonRegion::sigmoid, kScopeRadius);
    auto control = std::make_shared<SceneControl>();
    control->pressure_since_s[static_cast<std::size_t>(ColonRegion::sigmoid)] = 0.0;
    control->pressure_stiffness_N_per_mm2 = 1.0;
    control->pressure_max_force_N = 50.0;
    const AbdominalPressure hand(control);
    std::vector<NodalLoad> loads;
    hand.add_scope_loads(testing::three_node_view(sigmoid, 15.0), loads);
    ASSERT_EQ(loads.size(), 2u);
    const double scale = 50.0 / std::hypot(18.25, 116.5);
    EXPECT_NEAR(loads[0].force_N.y(), -18.25 * scale, 1e-12);
    EXPECT_NEAR(loads[1].force_N.z(), -116.5 * scale, 1e-12);
    EXPECT_NEAR(loads[1].stiffness_N_per_mm(2, 2), 10.0 * scale, 1e-12);
    EXPECT_NEAR((loads[0].force_N + loads[1].force_N).norm(), 50.0, 1e-12);

    // A softer hand (0.07: 8.25 N net) stays below the limit and is the spring itself.
    control->pressure_stiffness_N_per_mm2 = 0.07;
    loads.clear();
    hand.add_scope_loads(testing::three_node_view(sigmoid, 15.0), loads);
    ASSERT_EQ(loads.size(), 2u);
    EXPECT_NEAR(loads[1].force_N.z(), -8.155, 1e-12);
    EXPECT_NEAR(loads[1].stiffness_N_per_mm(2, 2), 0.7, 1e-12);
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

// The wheels' law (holds_curvature): the section's elements, and only they, are bent at rest
// towards theta0 / L_bend about a0 x d (a0 the axis at the section's base), turned at the wheels'
// rate pi rad/s of section angle, and let go at the same rate when the window ends.
TEST(TipSteering, TheWheelsTurnTheSectionsCurvatureAtTheirRateAndHoldIt) {
    const ColonTube tube =
        single_bend(120.0, 40.0, M_PI / 2.0, 15.0, ColonRegion::sigmoid, kScopeRadius);
    SteeringWindow window;
    window.start_s = 0.0;
    window.end_s = 5.0;
    window.gain = 1.0;
    window.holds_curvature = true;
    const TipSteering steering({window}, tube, 1.0e6, 10.0);
    WorldEffectView view = straight_scope_with_tilted_tip(tube, 0.0);
    std::vector<NodalLoad> loads;
    steering.add_scope_loads(view, loads);
    EXPECT_TRUE(loads.empty());  // no couple: the curvature does it

    // The centerline point 40 mm along the bend from the tip (120, 0, 0): base axis +x.
    std::size_t j = 0;
    while (tube.arc_length_mm(j) < 160.0)
        ++j;
    const Eigen::Vector3d d =
        (tube.points()[j].position_mm - Eigen::Vector3d(120, 0, 0)).normalized();
    const double theta0 = std::acos(d.x());
    const Eigen::Vector3d axis = Eigen::Vector3d::UnitX().cross(d).normalized();
    const double step_per_mm = M_PI * view.time_step_s / 80.0;  // the wheels' rate over L_bend
    std::vector<Eigen::Vector3d> curvature(11, Eigen::Vector3d::Zero());
    steering.add_rest_curvature(view, curvature);
    for (std::size_t e = 0; e < 11; ++e) {
        const Eigen::Vector3d expected =
            e >= 3 ? Eigen::Vector3d(step_per_mm * axis) : Eigen::Vector3d::Zero();
        EXPECT_LT((curvature[e] - expected).norm(), 1e-12) << "element " << e;
    }
    // Held at theta0 / L_bend once the wheels got there (theta0 / pi s; 1 s is ample).
    for (int k = 1; k <= 100; ++k) {
        view.time_s = 1.0 + 0.01 * k;
        curvature.assign(11, Eigen::Vector3d::Zero());
        steering.add_rest_curvature(view, curvature);
    }
    EXPECT_NEAR(theta0, 0.5, 0.1);
    EXPECT_LT((curvature[10] - theta0 / 80.0 * axis).norm(), 1e-12) << curvature[10].transpose();
    // Let go: back towards straight at the same rate.
    view.time_s = 5.0;
    curvature.assign(11, Eigen::Vector3d::Zero());
    steering.add_rest_curvature(view, curvature);
    EXPECT_NEAR(curvature[10].norm(), theta0 / 80.0 - step_per_mm, 1e-12);
}

// The world bends the section as commanded: a scope held in a wide bend with its tip at the
// bend's start angulates (the tip's axis turns by about the commanded angle within a second).
TEST(TipSteering, TheWorldBendsTheSectionToTheHeldCurvature) {
    nlohmann::json doc = nlohmann::json::parse(R"({
    "colon": {"bundled": "single_bend", "lead_mm": 300, "bend_radius_mm": 60, "bend_angle_deg": 90,
              "inner_radius_mm": 30},
    "scope": {"model": "cf_q160l", "length_mm": 400, "elements": 40},
    "initial_insertion_mm": 300,
    "procedure": [{"action": "hold", "start_s": 0, "end_s": 1.0}],
    "steering": [{"start_s": 0, "end_s": 1.0, "gain": 1.0, "holds_curvature": true}]
  })");
    const Scenario s = read_scenario(doc, "s.json");
    ASSERT_TRUE(s.steering.at(0).holds_curvature);
    auto world = build_world(s);
    const SimulationSummary sum = run_simulation(*world, s, {});
    ASSERT_TRUE(sum.complete) << sum.message;
    const std::size_t tip = world->scope_node_count() - 1;
    const Eigen::Vector3d base_axis = world->node_axis(tip - 8);
    const Eigen::Vector3d tip_axis = world->node_axis(tip);
    const double bend = std::acos(std::clamp(base_axis.dot(tip_axis), -1.0, 1.0));
    // The point 40 mm into a 60 mm bend lies 0.33 rad (its chord's half angle) off the axis at
    // the tip; from the base 80 mm behind, a little less. The section bends that far, not more.
    EXPECT_GT(bend, 0.2);
    EXPECT_LT(bend, 0.45);
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

/// scenario_with_pressure's push at 50 mm/s, run for 3 s, with its pressure window changed.
nlohmann::json pushed_for_3_s_pressed(double start_s, double end_s, double stiffness_N_per_mm2) {
    nlohmann::json doc = scenario_with_pressure();
    doc["procedure"][0]["end_s"] = 3.0;
    doc["abdominal_pressure"][0]["start_s"] = start_s;
    doc["abdominal_pressure"][0]["end_s"] = end_s;
    doc["abdominal_pressure"][0]["stiffness_N_per_mm2"] = stiffness_N_per_mm2;
    return doc;
}

TEST(AbdominalPressure, TheHandsForceOnTheScopeIsReportedOnlyWhileItPresses) {
    // The window is [2, 2.5) s with a 0.1 s ramp, on a scope pushed at 50 mm/s into a 115 degree
    // bend whose outer wall it bows against by then: the world reports the hand's net force on
    // the scope while the window is open, none before or after, and the run's summary keeps its
    // peak and time.
    const Scenario s = read_scenario(pushed_for_3_s_pressed(2.0, 2.5, 0.5), "s.json");
    auto world = build_world(s);
    double before_N = 0, during_peak_N = 0, after_N = 0;
    SimulationCallbacks callbacks;
    callbacks.on_step = [&](const World& w, const WorldStepReport&) {
        const double f = w.effect_force_N("abdominal_pressure");
        EXPECT_TRUE(std::isfinite(f));
        if (w.time_s() < 2.0 - 1e-9)
            before_N = std::max(before_N, f);
        else if (w.time_s() < 2.5 - 1e-9)
            during_peak_N = std::max(during_peak_N, f);
        else if (w.time_s() > 2.5 + 1e-9)
            after_N = std::max(after_N, f);
    };
    const SimulationSummary sum = run_simulation(*world, s, callbacks);
    ASSERT_TRUE(sum.complete) << sum.message;
    EXPECT_EQ(before_N, 0.0);
    EXPECT_EQ(after_N, 0.0);
    EXPECT_GT(during_peak_N, 0.1);
    EXPECT_DOUBLE_EQ(sum.max_assistant_pressure_force_N, during_peak_N);
    EXPECT_GT(sum.assistant_pressing_s, 0.0);
    EXPECT_LE(sum.assistant_pressing_s, 0.5 + 1e-9);
    EXPECT_LE(sum.assistant_pressure_impulse_Ns, during_peak_N * sum.assistant_pressing_s + 1e-12);
    EXPECT_EQ(world->effect_force_N("no_such_effect"), 0.0);
}

TEST(AbdominalPressure, AFirmHandPressedAtOnceKeepsTheStepPhysical) {
    // The firmest hand the scenario takes (1 N/mm per mm of scope), at once, on a scope pushed
    // at 50 mm/s into a 115 degree bend: 10 N/mm on a node of 2.5 g, forty times its M/h^2 at a
    // 5 ms step. Applied explicitly (the force from the step's start) such a spring overshoots
    // by more than it corrects; it did: a 4,347 N contact at 2.12 s. Taken implicitly the run
    // stays with the forces of a 50 mm/s push: a few newtons at the handle.
    nlohmann::json doc = pushed_for_3_s_pressed(0.1, 3.0, 1.0);
    doc["abdominal_pressure"][0]["ramp_s"] = 0.0;
    const Scenario s = read_scenario(doc, "s.json");
    auto world = build_world(s);
    const SimulationSummary sum = run_simulation(*world, s, {});
    ASSERT_TRUE(sum.complete) << sum.message;
    EXPECT_LT(sum.max_handle_force_N, 20.0);
    EXPECT_LT(sum.max_contact_force_N, 50.0);
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
