// Scenario files (model/scenario): strict reading with errors that name the field, the
// procedure's validation, the ProcedurePlayer's command timeline against hand-computed depths
// and rolls, and the sampling of a short run.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "model/colon/colon_beam.hpp"
#include "model/model_error.hpp"
#include "model/scenario/procedure.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"

namespace scopekin::model {
namespace {

/// A valid world scenario in a straight tube; tests change one thing at a time.
nlohmann::json base() {
    return nlohmann::json::parse(R"({
    "colon": {"bundled": "straight_tube", "length_mm": 400, "inner_radius_mm": 15, "region": "rectum"},
    "scope": {"model": "cf_q160l", "length_mm": 300, "elements": 30},
    "initial_insertion_mm": 20,
    "procedure": [{"action": "advance", "start_s": 0, "end_s": 1, "speed_mm_per_s": 10}]
  })");
}

/// Expects ModelError whose message contains every fragment.
void expect_error(const nlohmann::json& doc, std::initializer_list<std::string> fragments) {
    try {
        read_scenario(doc, "s.json");
        ADD_FAILURE() << "no error; expected one mentioning '" << *fragments.begin() << "'";
    } catch (const ModelError& e) {
        for (const std::string& f : fragments)
            EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    }
}

TEST(ScenarioReader, EveryActionIsParsed) {
    nlohmann::json doc = base();
    doc["procedure"] = nlohmann::json::parse(R"([
    {"action": "advance", "start_s": 0, "end_s": 1, "speed_mm_per_s": 10},
    {"action": "withdraw", "start_s": 1, "end_s": 2, "speed_mm_per_s": 5},
    {"action": "hold", "start_s": 2.5, "end_s": 3},
    {"action": "push", "start_s": 3, "end_s": 4, "force_N": 2.5},
    {"action": "twist", "start_s": 4, "end_s": 5, "torque_Nmm": -30},
    {"action": "rotate", "start_s": 5, "end_s": 6, "speed_deg_per_s": -45},
    {"action": "dither", "start_s": 6, "end_s": 7, "amplitude_mm": 3, "frequency_Hz": 2}
  ])");
    const Scenario s = read_scenario(doc, "s.json");
    ASSERT_EQ(s.kind, ScenarioKind::world);
    const auto& a = s.procedure.actions();
    ASSERT_EQ(a.size(), 7u);
    EXPECT_EQ(a[0].kind, ActionKind::advance);
    EXPECT_EQ(a[0].speed_mm_per_s, 10.0);
    EXPECT_EQ(a[1].kind, ActionKind::withdraw);
    EXPECT_EQ(a[1].speed_mm_per_s, 5.0);
    EXPECT_EQ(a[2].kind, ActionKind::hold);
    EXPECT_EQ(a[2].start_s, 2.5);
    EXPECT_EQ(a[3].kind, ActionKind::push);
    EXPECT_EQ(a[3].force_N, 2.5);
    EXPECT_EQ(a[4].kind, ActionKind::twist);
    EXPECT_EQ(a[4].torque_Nmm, -30.0);
    EXPECT_EQ(a[5].kind, ActionKind::rotate);
    EXPECT_EQ(a[5].speed_deg_per_s, -45.0);
    EXPECT_EQ(a[6].kind, ActionKind::dither);
    EXPECT_EQ(a[6].amplitude_mm, 3.0);
    EXPECT_EQ(a[6].frequency_Hz, 2.0);
    EXPECT_EQ(s.procedure.end_s(), 7.0);
}

TEST(ScenarioReader, Defaults) {
    nlohmann::json doc = nlohmann::json::parse(R"({
    "colon": {"bundled": "default"},
    "scope": {"model": "cf_q160l"},
    "procedure": [{"action": "hold", "start_s": 0, "end_s": 1}]
  })");
    const Scenario s = read_scenario(doc, "s.json");
    EXPECT_EQ(s.scope.length_mm, 1700.0);
    EXPECT_EQ(s.scope.elements, 170u);
    EXPECT_EQ(s.scope.radius_mm, 6.65);
    EXPECT_EQ(s.scope.section.bending_stiffness_y_Nmm2, 35000.0);
    EXPECT_EQ(s.settings.time_step_s, 0.01);
    EXPECT_EQ(s.settings.newton_iterations, 1);
    EXPECT_FALSE(s.settings.telescoping.enabled);  // off unless a scenario asks for it
    // Thesis Eq. 4.15 in the Hz convention: a' = 2 pi 0.3864, b' = 0.0164 / (2 pi).
    EXPECT_NEAR(s.settings.damping.mass_coefficient_per_s, 2.0 * M_PI * 0.3864, 1e-12);
    EXPECT_NEAR(s.settings.damping.stiffness_coefficient_s, 0.0164 / (2.0 * M_PI), 1e-12);
    EXPECT_EQ(s.settings.gravity_mm_per_s2, Eigen::Vector3d(0, 0, -9810));
    EXPECT_EQ(s.settings.initial_insertion_mm, 0.0);
    EXPECT_EQ(s.settings.contact.friction_coefficient, 0.25);
    EXPECT_EQ(s.settings.contact.activation_distance_mm, 2.0);
    EXPECT_EQ(s.settings.contact.wall_compliance_mm_per_N, 0.28);
    EXPECT_EQ(s.settings.contact.max_sweeps, 2000u);
    EXPECT_EQ(s.outputs.sample_rate_Hz, 30.0);
    EXPECT_TRUE(s.outputs.nodes_from_tip_mm.empty());
    EXPECT_FALSE(s.outputs.contacts_file);
    const auto defaults = default_colon_properties();
    for (std::size_t i = 0; i < 8; ++i)
        EXPECT_EQ(s.colon_properties[i].young_modulus_kPa, defaults[i].young_modulus_kPa);
    ASSERT_TRUE(s.colon.has_value());
    EXPECT_EQ(s.colon->name(), "default");
}

TEST(ScenarioReader, EverySettingIsRead) {
    nlohmann::json doc = base();
    doc["scope"] = {{"model", "cf_q160l"},
                    {"length_mm", 500},
                    {"elements", 50},
                    {"bending_stiffness_Nmm2", 40000},
                    {"radius_mm", 6}};
    doc["colon_regions"] = nlohmann::json::parse(
        R"({"sigmoid": {"young_modulus_kPa": 500, "wall_thickness_mm": 3, "attachment": "fixed"},
          "transverse": {"mesentery_stiffness_N_per_mm2": 0.01}})");
    doc["gravity_mm_per_s2"] = {0, -9810, 0};
    doc["solver"] = nlohmann::json::parse(R"({"time_step_s": 0.005, "newton_iterations": 3,
      "damping": {"alpha_hz_convention": 0.5, "beta_hz_convention": 0.01},
      "contact": {"friction_coefficient": 0.3, "friction_zones": [{"from_tip_mm": 0, "to_tip_mm": 100, "coefficient": 0.4}],
                  "activation_distance_mm": 3, "wall_compliance_mm_per_N": 0.1, "tolerance_N": 1e-5,
                  "max_sweeps": 500, "relaxation": 1.2}})");
    doc["outputs"] = nlohmann::json::parse(
        R"({"sample_rate_Hz": 100, "nodes_from_tip_mm": [0, 200], "contacts_file": true})");
    doc["telescoping"] = nlohmann::json::parse(
        R"({"enabled": true, "onset_drag_N": 2, "stiffening_drag_N": 3, "recoil_time_s": 10,
            "rate_per_N_s": 0.5, "max_fraction": 0.4})");
    const Scenario s = read_scenario(doc, "s.json");
    EXPECT_TRUE(s.settings.telescoping.enabled);
    EXPECT_EQ(s.settings.telescoping.onset_drag_N, 2.0);
    EXPECT_EQ(s.settings.telescoping.stiffening_drag_N, 3.0);
    EXPECT_EQ(s.settings.telescoping.recoil_time_s, 10.0);
    EXPECT_EQ(s.settings.telescoping.rate_per_N_s, 0.5);
    EXPECT_EQ(s.settings.telescoping.max_fraction, 0.4);
    EXPECT_EQ(s.scope.length_mm, 500.0);
    EXPECT_EQ(s.scope.elements, 50u);
    EXPECT_EQ(s.scope.radius_mm, 6.0);
    EXPECT_EQ(s.scope.section.bending_stiffness_z_Nmm2, 40000.0);
    const auto& sig = s.colon_properties[static_cast<std::size_t>(ColonRegion::sigmoid)];
    EXPECT_EQ(sig.young_modulus_kPa, 500.0);
    EXPECT_EQ(sig.wall_thickness_mm, 3.0);
    EXPECT_EQ(sig.attachment, ColonAttachment::fixed);
    EXPECT_EQ(s.colon_properties[static_cast<std::size_t>(ColonRegion::transverse)]
                  .mesentery_stiffness_N_per_mm2,
              0.01);
    EXPECT_EQ(s.settings.gravity_mm_per_s2, Eigen::Vector3d(0, -9810, 0));
    EXPECT_EQ(s.settings.time_step_s, 0.005);
    EXPECT_EQ(s.settings.newton_iterations, 3);
    EXPECT_NEAR(s.settings.damping.mass_coefficient_per_s, 2.0 * M_PI * 0.5, 1e-12);
    EXPECT_EQ(s.settings.contact.friction_coefficient, 0.3);
    ASSERT_EQ(s.settings.contact.friction_zones.size(), 1u);
    EXPECT_EQ(s.settings.contact.friction_zones[0].coefficient, 0.4);
    EXPECT_EQ(s.settings.contact.activation_distance_mm, 3.0);
    EXPECT_EQ(s.settings.contact.wall_compliance_mm_per_N, 0.1);
    EXPECT_EQ(s.settings.contact.tolerance_N, 1e-5);
    EXPECT_EQ(s.settings.contact.max_sweeps, 500u);
    EXPECT_EQ(s.settings.contact.relaxation, 1.2);
    EXPECT_EQ(s.outputs.sample_rate_Hz, 100.0);
    EXPECT_TRUE(s.outputs.contacts_file);
    // 500 mm in 50 elements: node 50 is the tip, 200 mm from the tip is node 30.
    EXPECT_EQ(output_nodes(s), (std::vector<std::size_t>{50, 30}));
}

TEST(ScenarioReader, WaypointColon) {
    nlohmann::json doc = base();
    doc["colon"] = nlohmann::json::parse(R"({"waypoints": [
      {"position_mm": [0, 0, 0], "inner_radius_mm": 15, "region": "rectum"},
      {"position_mm": [100, 0, 0], "inner_radius_mm": 15, "region": "sigmoid"},
      {"position_mm": [200, 50, 0], "inner_radius_mm": 14, "region": "sigmoid"}], "spacing_mm": 5})");
    const Scenario s = read_scenario(doc, "s.json");
    ASSERT_TRUE(s.colon.has_value());
    EXPECT_GT(s.colon->point_count(), 40u);  // > 210 mm of centerline in pieces of at most 5 mm
    EXPECT_EQ(s.colon->points().front().region, ColonRegion::rectum);
    EXPECT_EQ(s.colon->points().back().region, ColonRegion::sigmoid);
}

TEST(ScenarioReader, UnknownKeysAreRejectedWithTheirPath) {
    nlohmann::json doc = base();
    doc["solver"] = {{"contact", {{"max_sweep", 3}}}};
    expect_error(doc, {"s.json: solver.contact.max_sweep: unknown key", "max_sweeps"});
    doc = base();
    doc["procedure"][0]["speed"] = 3;
    expect_error(doc, {"s.json: procedure[0].speed: unknown key", "speed_mm_per_s"});
    doc = base();
    doc["colour"] = 1;
    expect_error(doc, {"s.json: colour: unknown key"});
    doc = base();
    doc["colon_regions"] = {{"sigmoid_colon", {{"young_modulus_kPa", 3}}}};
    expect_error(doc, {"colon_regions.sigmoid_colon: unknown region", "sigmoid"});
    doc = base();
    doc["procedure"][0]["action"] = "jump";
    expect_error(doc, {"procedure[0].action: unknown action 'jump'"});
}

TEST(ScenarioReader, KindNeedsExactlyOneOfBeamOrColon) {
    nlohmann::json doc = base();
    doc["beam"] = nlohmann::json::object();
    expect_error(doc, {"s.json", "both 'beam'", "'colon'"});
    doc = base();
    doc.erase("colon");
    expect_error(doc, {"s.json", "neither 'colon'", "'beam'"});
}

TEST(ScenarioReader, FreeBeamIsABeamProblem) {
    const nlohmann::json doc = nlohmann::json::parse(R"({
    "description": "cantilever",
    "beam": {"straight": {"length_mm": 100, "elements": 10}, "section": "cf_q160l"},
    "supports": [{"node": 0}], "loads": [{"node": 10, "force_N": [0, -1, 0]}]
  })");
    const Scenario s = read_scenario(doc, "s.json");
    EXPECT_EQ(s.kind, ScenarioKind::free_beam);
    ASSERT_TRUE(s.beam_problem.has_value());
    EXPECT_EQ(s.beam_problem->beam.node_count(), 11u);
    EXPECT_EQ(s.description, "cantilever");
    nlohmann::json bad = doc;
    bad["procedure"] = nlohmann::json::array();
    expect_error(bad, {"s.json: procedure: unknown key"});
}

TEST(ScenarioReader, ProcedureGoingBackwardsOrOverlappingIsRejected) {
    nlohmann::json doc = base();
    doc["procedure"] = nlohmann::json::parse(R"([
    {"action": "advance", "start_s": 2, "end_s": 3, "speed_mm_per_s": 10},
    {"action": "hold", "start_s": 0, "end_s": 1}])");
    expect_error(doc, {"s.json: procedure[1].start_s", "goes backwards in time"});
    doc["procedure"] = nlohmann::json::parse(R"([
    {"action": "advance", "start_s": 0, "end_s": 2, "speed_mm_per_s": 10},
    {"action": "hold", "start_s": 1.5, "end_s": 3}])");
    expect_error(doc, {"s.json: procedure[1].start_s", "overlaps"});
    doc["procedure"] = nlohmann::json::parse(R"([{"action": "hold", "start_s": 2, "end_s": 2}])");
    expect_error(doc, {"procedure[0].end_s", "later than start_s"});
    doc["procedure"] = nlohmann::json::array();
    expect_error(doc, {"procedure: needs at least one action"});
    doc["procedure"] =
        nlohmann::json::parse(R"([{"action": "hold", "start_s": 0, "end_s": 3601}])");
    expect_error(doc, {"procedure[0].end_s", "1 h"});
}

TEST(ScenarioReader, ColonsTooLongToSampleAreRefusedBeforeAllocating) {
    // Found by fuzz.scenario: a bend radius of 4e68 mm overflowed the piece count (undefined
    // behaviour, then a vector of billions of points).  At most 100,000 centerline points.
    nlohmann::json doc = base();
    doc["colon"] = {{"bundled", "single_bend"},
                    {"lead_mm", 150},
                    {"bend_radius_mm", 4e68},
                    {"bend_angle_deg", 115},
                    {"inner_radius_mm", 15}};
    expect_error(doc, {"s.json: colon", "single_bend bend_radius_mm", "100000 centerline points"});
    doc["colon"]["bend_radius_mm"] = 40;
    doc["colon"]["lead_mm"] = 1e7;
    expect_error(doc, {"s.json: colon", "single_bend lead_mm", "100000 centerline points"});
    doc["colon"] = {{"bundled", "straight_tube"}, {"length_mm", 1e300}, {"inner_radius_mm", 15}};
    expect_error(doc, {"s.json: colon", "straight_tube length_mm", "100000 centerline points"});
    doc["colon"] = nlohmann::json::parse(R"({"spacing_mm": 1e-6, "waypoints": [
      {"position_mm": [0, 0, 0], "inner_radius_mm": 15, "region": "rectum"},
      {"position_mm": [200, 0, 0], "inner_radius_mm": 15, "region": "rectum"}]})");
    expect_error(doc, {"s.json: colon", "100000 centerline points"});
}

TEST(ScenarioReader, ImpossibleColonsAreRejected) {
    nlohmann::json doc = base();
    // A loop that comes back onto its own start: the lumens overlap.
    doc["colon"] = nlohmann::json::parse(R"({"waypoints": [
      {"position_mm": [0, 0, 0], "inner_radius_mm": 15, "region": "rectum"},
      {"position_mm": [200, 0, 0], "inner_radius_mm": 15, "region": "rectum"},
      {"position_mm": [200, 150, 0], "inner_radius_mm": 15, "region": "rectum"},
      {"position_mm": [100, -100, 0], "inner_radius_mm": 15, "region": "rectum"}]})");
    expect_error(doc, {"s.json: colon", "intersects itself"});
    doc = base();
    doc["colon"]["inner_radius_mm"] = 5;  // narrower than the 6.65 mm scope
    expect_error(doc, {"s.json: colon", "not larger than the scope's radius"});
    doc = base();
    doc["colon"] = nlohmann::json::parse(R"({"waypoints": [
      {"position_mm": [0, 0, 0], "inner_radius_mm": 15, "region": "rectum"},
      {"position_mm": [100, 0, 0], "inner_radius_mm": 6, "region": "rectum"}]})");
    expect_error(
        doc, {"s.json: colon.waypoints[1].inner_radius_mm", "not larger than the scope's radius"});
    doc = base();
    doc["colon"] = nlohmann::json::parse(R"({"waypoints": [
      {"position_mm": [0, 0, 0], "inner_radius_mm": 15, "region": "sigmoid"},
      {"position_mm": [100, 0, 0], "inner_radius_mm": 15, "region": "rectum"}]})");
    expect_error(doc, {"s.json: colon", "region rectum comes after sigmoid"});
    doc = base();
    doc["colon"] = {{"bundled", "single_bend"},
                    {"lead_mm", 100},
                    {"bend_radius_mm", 40},
                    {"bend_angle_deg", 200},
                    {"inner_radius_mm", 15}};
    expect_error(doc, {"colon.bend_angle_deg", "<= 180"});
    doc = base();
    doc["colon"] = {{"bundled", "sigmoid_loop"}};
    expect_error(doc, {"colon.bundled: unknown bundled colon 'sigmoid_loop'"});
}

TEST(ScenarioReader, BadNumbersAreRejected) {
    nlohmann::json doc = base();
    doc["procedure"][0]["speed_mm_per_s"] = -10;
    expect_error(doc, {"procedure[0].speed_mm_per_s"});
    doc = base();
    doc["procedure"][0]["speed_mm_per_s"] = "fast";
    expect_error(doc, {"procedure[0].speed_mm_per_s: expected a number"});
    doc = base();
    doc["procedure"][0]["start_s"] = -1;
    expect_error(doc, {"procedure[0].start_s"});
    doc = base();
    doc["solver"] = {{"time_step_s", 0.5}};
    expect_error(doc, {"s.json: solver.time_step_s", "outside [0.001, 0.033]"});
    doc = base();
    doc["scope"]["elements"] = 1;
    expect_error(doc, {"s.json: scope.elements"});
    doc = base();
    doc["scope"]["elements"] = 2.5;
    expect_error(doc, {"s.json: scope.elements: expected a non-negative integer"});
    doc = base();
    doc["scope"]["model"] = "cf_h180";
    expect_error(doc, {"scope.model: unknown scope model"});
    doc = base();
    doc["initial_insertion_mm"] = 300;
    expect_error(doc, {"s.json: initial_insertion_mm", "shorter than the scope"});
    doc = base();
    doc["solver"] = {{"contact", {{"relaxation", 2}}}};
    expect_error(doc, {"solver.contact.relaxation", "(0, 2)"});
    doc = base();
    doc["solver"] = {{"contact", {{"friction_coefficient", -0.1}}}};
    expect_error(doc, {"solver.contact.friction_coefficient"});
    doc = base();
    doc["telescoping"] = {{"max_fraction", 1.0}};
    expect_error(doc, {"s.json: telescoping.max_fraction", "[0, 1)"});
    doc = base();
    doc["telescoping"] = {{"onset_drag_N", -1}};
    expect_error(doc, {"telescoping.onset_drag_N"});
    doc = base();
    doc["telescoping"] = {{"enabled", "yes"}};
    expect_error(doc, {"telescoping.enabled"});
    doc = base();
    doc["telescoping"] = {{"pleats", 3}};
    expect_error(doc, {"telescoping", "pleats"});
    doc = base();
    doc["outputs"] = {{"sample_rate_Hz", 200}};
    expect_error(doc, {"outputs.sample_rate_Hz", "above the step rate"});
    doc = base();
    doc["outputs"] = {{"nodes_from_tip_mm", {0, 301}}};
    expect_error(doc, {"outputs.nodes_from_tip_mm[1]", "beyond the scope's length"});
    doc = base();
    doc["colon_regions"] = {{"sigmoid", {{"attachment", "glued"}}}};
    expect_error(doc, {"colon_regions.sigmoid.attachment: unknown attachment"});
    doc = base();
    doc["procedure"] = nlohmann::json::parse(
        R"([{"action": "dither", "start_s": 0, "end_s": 1, "amplitude_mm": 2, "frequency_Hz": 30}])");
    expect_error(doc, {"procedure[0].frequency_Hz", "too fast"});
    doc["procedure"] = nlohmann::json::parse(
        R"([{"action": "dither", "start_s": 0, "end_s": 1, "amplitude_mm": 0, "frequency_Hz": 1}])");
    expect_error(doc, {"procedure[0].amplitude_mm"});
    doc["procedure"] =
        nlohmann::json::parse(R"([{"action": "hold", "start_s": 0, "end_s": 0.005}])");
    expect_error(doc, {"procedure[0]", "shorter than one time step"});
}

TEST(ScenarioReader, PrescribedDepthMustStayInsideTheScopeRange) {
    nlohmann::json doc = base();  // starts at 20 mm
    doc["procedure"] = nlohmann::json::parse(R"([
    {"action": "advance", "start_s": 0, "end_s": 1, "speed_mm_per_s": 10},
    {"action": "withdraw", "start_s": 1, "end_s": 3, "speed_mm_per_s": 20}])");
    // 20 + 10 - 40 = -10 mm at t = 3 s.
    expect_error(doc, {"procedure[1] (withdraw)", "-10 mm at t = 3 s", ">= 0"});
    doc["procedure"] = nlohmann::json::parse(
        R"([{"action": "dither", "start_s": 0, "end_s": 2, "amplitude_mm": 25, "frequency_Hz": 1}])");
    // 20 - 25 = -5 mm at the trough, t = 0.75 s.
    expect_error(doc, {"procedure[0] (dither)", "-5 mm at t = 0.75 s"});
    doc["procedure"] = nlohmann::json::parse(
        R"([{"action": "advance", "start_s": 0, "end_s": 10, "speed_mm_per_s": 30}])");
    expect_error(doc, {"procedure[0] (advance)", "320 mm", "below the scope's length (300 mm)"});
    // After a push the depth is unknown until run time: not an input error.
    doc["procedure"] = nlohmann::json::parse(R"([
    {"action": "push", "start_s": 0, "end_s": 1, "force_N": 1},
    {"action": "withdraw", "start_s": 1, "end_s": 3, "speed_mm_per_s": 20}])");
    EXPECT_NO_THROW(read_scenario(doc, "s.json"));
}

ProcedureAction act(ActionKind kind, double start, double end) {
    ProcedureAction a;
    a.kind = kind;
    a.start_s = start;
    a.end_s = end;
    return a;
}

// A world model (scopekin discrepancy's --model): the run's keys are not read, the effects are
// checked but left to each run, and the runner's initial insertion is checked as the file's.
TEST(ScenarioReader, WorldModelLeavesTheRunAndTheEffectsToTheRunner) {
    nlohmann::json doc = base();
    doc.erase("initial_insertion_mm");
    doc["procedure"] = "not read";
    doc["truth_effects"] = nlohmann::json::parse(R"([{"name": "ei_scale", "factor": 0.9}])");
    doc["abdominal_pressure"] = nlohmann::json::parse(R"([{"start_s": 0, "end_s": 1}])");
    Scenario m = read_world_model(doc, "m.json");
    EXPECT_TRUE(m.procedure.actions().empty());
    EXPECT_TRUE(m.effects.empty());
    const auto scene = scene_effects(m);
    ASSERT_EQ(scene.size(), 1u);
    EXPECT_EQ(scene[0]->name(), "abdominal_pressure");
    set_initial_insertion(m, 25.0);
    EXPECT_EQ(m.settings.initial_insertion_mm, 25.0);
    try {
        set_initial_insertion(m, 300.0);
        ADD_FAILURE() << "no error for an insertion of the scope's whole length";
    } catch (const ModelError& e) {
        EXPECT_NE(std::string(e.what()).find(
                      "m.json: initial_insertion_mm: 300 mm must be shorter than the scope"),
                  std::string::npos)
            << e.what();
    }
    doc["truth_effects"] = nlohmann::json::parse(R"([{"name": "no_such_effect"}])");
    EXPECT_THROW(read_world_model(doc, "m.json"), ModelError);
    EXPECT_THROW(read_world_model(nlohmann::json::parse(R"({"beam": {}})"), "b.json"), ModelError);
}

TEST(ScenarioReader, ModelFileFillsInAndJoinsTruthEffects) {
    // A model file (as scopekin discrepancy writes) next to a scenario that names it.
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / "scopekin_test_model_file";
    std::filesystem::create_directories(dir / "fit");
    std::ofstream(dir / "fit" / "model.json")
        << R"({"colon": {"bundled": "straight_tube", "length_mm": 300, "inner_radius_mm": 15},
    "scope": {"model": "cf_q160l", "length_mm": 400, "elements": 40}, "solver": {"time_step_s": 0.02},
    "truth_effects": [{"name": "ei_scale", "factor": 0.9}]})";
    std::ofstream(dir / "scenario.json")
        << R"({"model": "fit/model.json", "solver": {"time_step_s": 0.01},
    "procedure": [{"action": "advance", "start_s": 0, "end_s": 1, "speed_mm_per_s": 10}],
    "truth_effects": [{"name": "viscoadhesive_friction"}]})";
    const Scenario s = read_scenario_file((dir / "scenario.json").string());
    EXPECT_EQ(s.colon->name(), "straight_tube");  // from the model
    EXPECT_EQ(s.scope.length_mm, 400.0);
    EXPECT_EQ(s.settings.time_step_s, 0.01);  // the scenario's own key wins
    ASSERT_EQ(s.effects.size(), 2u);          // joined, the model's first
    EXPECT_EQ(s.effects[0]->name(), "ei_scale");
    EXPECT_EQ(s.effects[1]->name(), "viscoadhesive_friction");

    std::ofstream(dir / "bad.json") << R"({"model": 3, "procedure": []})";
    EXPECT_THROW(read_scenario_file((dir / "bad.json").string()), ModelError);
    std::ofstream(dir / "missing.json") << R"({"model": "nowhere.json", "procedure": []})";
    EXPECT_THROW(read_scenario_file((dir / "missing.json").string()), ModelError);
    std::filesystem::remove_all(dir);
}

TEST(ProcedurePlayer, CommandTimelineMatchesHandComputedDepthsAndRolls) {
    std::vector<ProcedureAction> actions;
    actions.push_back(act(ActionKind::advance, 0, 2));
    actions.back().speed_mm_per_s = 10;  // 20 -> 40 mm
    // gap 2 .. 3: hold at 40 mm
    actions.push_back(act(ActionKind::dither, 3, 5));
    actions.back().amplitude_mm = 2;
    actions.back().frequency_Hz = 1;
    actions.push_back(act(ActionKind::rotate, 5, 6));
    actions.back().speed_deg_per_s = 90;  // roll 0 -> 90 deg
    actions.push_back(act(ActionKind::withdraw, 6, 7));
    actions.back().speed_mm_per_s = 4;
    ProcedurePlayer player(Procedure(actions), 20.0, 1000.0);
    const double h = 0.25;
    auto at = [&](double t_end) {
        return player.command(t_end - h, h, -1.0, -1.0);
    };  // world state unused here

    HandleCommand c = at(1.0);
    EXPECT_FALSE(c.force_controlled);
    EXPECT_FALSE(c.torque_controlled);
    EXPECT_NEAR(c.insertion_mm, 30.0, 1e-12);  // 20 + 10 * 1
    EXPECT_NEAR(c.roll_rad, 0.0, 1e-12);
    EXPECT_NEAR(at(2.0).insertion_mm, 40.0, 1e-12);
    EXPECT_NEAR(at(2.5).insertion_mm, 40.0, 1e-12);  // gap = hold
    EXPECT_NEAR(at(3.0).insertion_mm, 40.0, 1e-12);
    EXPECT_NEAR(at(3.25).insertion_mm, 42.0, 1e-12);  // 40 + 2 sin(2 pi 1 0.25)
    EXPECT_NEAR(at(3.5).insertion_mm, 40.0, 1e-12);   // sin(pi)
    EXPECT_NEAR(at(3.75).insertion_mm, 38.0, 1e-12);  // sin(3 pi / 2)
    EXPECT_NEAR(at(5.0).insertion_mm, 40.0, 1e-12);   // two whole periods
    c = at(5.5);
    EXPECT_NEAR(c.insertion_mm, 40.0, 1e-12);
    EXPECT_NEAR(c.roll_rad, 45.0 * M_PI / 180.0, 1e-12);
    EXPECT_NEAR(at(6.0).roll_rad, M_PI / 2.0, 1e-12);
    c = at(6.5);
    EXPECT_NEAR(c.insertion_mm, 38.0, 1e-12);    // 40 - 4 * 0.5
    EXPECT_NEAR(c.roll_rad, M_PI / 2.0, 1e-12);  // rotation kept
    EXPECT_NEAR(at(7.0).insertion_mm, 36.0, 1e-12);
    EXPECT_NEAR(at(7.25).insertion_mm, 36.0, 1e-12);  // beyond the end: the last value
    EXPECT_TRUE(player.warnings().empty());
}

TEST(ProcedurePlayer, DitherStartsFromTheDepthItFinds) {
    std::vector<ProcedureAction> actions;
    actions.push_back(act(ActionKind::dither, 0, 1));
    actions.back().amplitude_mm = 5;
    actions.back().frequency_Hz = 0.5;
    ProcedurePlayer player(Procedure(actions), 100.0, 1000.0);
    // 100 + 5 sin(2 pi 0.5 t): t = 0.1 -> 101.5451, t = 1 -> 100 + 5 sin(pi) = 100.
    EXPECT_NEAR(player.command(0.0, 0.1, 0, 0).insertion_mm, 100.0 + 5.0 * std::sin(M_PI * 0.1),
                1e-12);
    EXPECT_NEAR(player.command(0.9, 0.1, 0, 0).insertion_mm, 100.0, 1e-9);
}

TEST(ProcedurePlayer, PositionControlResumesFromTheWorldAfterPushAndTwist) {
    std::vector<ProcedureAction> actions;
    actions.push_back(act(ActionKind::push, 0, 1));
    actions.back().force_N = 3;
    actions.push_back(act(ActionKind::advance, 1, 2));
    actions.back().speed_mm_per_s = 10;
    actions.push_back(act(ActionKind::twist, 2, 3));
    actions.back().torque_Nmm = -20;
    actions.push_back(act(ActionKind::hold, 3, 4));
    ProcedurePlayer player(Procedure(actions), 50.0, 500.0, 0.1);
    const double h = 0.5;
    HandleCommand c = player.command(0.0, h, 50.0, 0.1);
    EXPECT_TRUE(c.force_controlled);
    EXPECT_EQ(c.push_force_N, 3.0);
    EXPECT_FALSE(c.torque_controlled);
    EXPECT_NEAR(c.roll_rad, 0.1, 1e-12);  // the roll is held during a push
    c = player.command(0.5, h, 61.0, 0.1);
    EXPECT_TRUE(c.force_controlled);
    // The push moved the scope to 73 mm (the world's depth at t = 1 s); the advance starts there.
    c = player.command(1.0, h, 73.0, 0.1);
    EXPECT_FALSE(c.force_controlled);
    EXPECT_NEAR(c.insertion_mm, 78.0, 1e-12);  // 73 + 10 * 0.5
    c = player.command(1.5, h, 78.0, 0.1);
    EXPECT_NEAR(c.insertion_mm, 83.0, 1e-12);
    c = player.command(2.0, h, 83.0, 0.1);
    EXPECT_TRUE(c.torque_controlled);
    EXPECT_EQ(c.torque_Nmm, -20.0);
    EXPECT_NEAR(c.insertion_mm, 83.0, 1e-12);  // depth held during a twist
    c = player.command(2.5, h, 83.0, -0.3);
    EXPECT_TRUE(c.torque_controlled);
    // The twist turned the scope to -0.7 rad (the world's roll at t = 3 s); the hold keeps it.
    c = player.command(3.0, h, 83.0, -0.7);
    EXPECT_FALSE(c.torque_controlled);
    EXPECT_NEAR(c.roll_rad, -0.7, 1e-12);
    EXPECT_NEAR(c.insertion_mm, 83.0, 1e-12);
}

TEST(ProcedurePlayer, DepthAfterAPushIsClampedWithAWarning) {
    std::vector<ProcedureAction> actions;
    actions.push_back(act(ActionKind::push, 0, 1));
    actions.back().force_N = -2;
    actions.push_back(act(ActionKind::withdraw, 1, 3));
    actions.back().speed_mm_per_s = 10;
    ProcedurePlayer player(Procedure(actions), 30.0, 500.0);
    player.command(0.0, 1.0, 30.0, 0.0);
    EXPECT_NEAR(player.command(1.0, 1.0, 15.0, 0.0).insertion_mm, 5.0, 1e-12);  // 15 - 10
    EXPECT_TRUE(player.warnings().empty());
    EXPECT_EQ(player.command(2.0, 1.0, 5.0, 0.0).insertion_mm, 0.0);  // 15 - 20 = -5, clamped
    ASSERT_EQ(player.warnings().size(), 1u);
    EXPECT_NE(player.warnings()[0].find("procedure[1] (withdraw)"), std::string::npos)
        << player.warnings()[0];
}

TEST(Simulation, SamplesAtTheOutputRateAndFollowsTheProcedure) {
    nlohmann::json doc = base();
    doc["gravity_mm_per_s2"] = {0, 0, 0};
    doc["procedure"] = nlohmann::json::parse(R"([
    {"action": "advance", "start_s": 0, "end_s": 0.1, "speed_mm_per_s": 100},
    {"action": "rotate", "start_s": 0.15, "end_s": 0.2, "speed_deg_per_s": 200}])");
    doc["outputs"] = {{"sample_rate_Hz", 30}, {"nodes_from_tip_mm", {0, 100}}};
    const Scenario s = read_scenario(doc, "s.json");
    auto world = build_world(s);
    std::vector<WorldRow> samples;
    SimulationCallbacks callbacks;
    callbacks.on_sample = [&](const WorldRow& x, const World&) { samples.push_back(x); };
    std::size_t progress_calls = 0;
    callbacks.on_progress = [&](const SimulationProgress&) { ++progress_calls; };
    const SimulationSummary sum = run_simulation(*world, s, callbacks);
    ASSERT_TRUE(sum.complete) << sum.message;
    EXPECT_EQ(sum.steps, 20u);  // 0.2 s in steps of 0.01 s
    EXPECT_EQ(progress_calls, 20u);
    // Sample times k / 30 s, each taken at the first step at or after it: 0, 0.04, 0.07, 0.1,
    // 0.14, 0.17, 0.2.
    const std::vector<double> expected{0.0, 0.04, 0.07, 0.10, 0.14, 0.17, 0.20};
    ASSERT_EQ(samples.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i)
        EXPECT_NEAR(samples[i].time_s, expected[i], 1e-9) << i;
    EXPECT_EQ(sum.samples, expected.size());
    // Straight scope in a straight tube without gravity: no contact; the depth is prescribed.
    EXPECT_NEAR(samples[3].insertion_depth_mm, 30.0, 1e-9);  // 20 + 100 * 0.1
    EXPECT_NEAR(samples[4].insertion_depth_mm, 30.0, 1e-9);  // gap: hold
    EXPECT_NEAR(samples.back().roll_deg, 10.0, 1e-6);        // 200 deg/s for 0.05 s
    // Tip and node positions: the straight scope slid in; 1e-3 mm allows the axial strain from its
    // own inertia (EA = 3.17 kN, the scope just stopped accelerating).
    EXPECT_NEAR(samples[3].tip_mm.x(), 30.0, 1e-3);
    ASSERT_EQ(samples[3].nodes_mm.size(), 2u);
    EXPECT_NEAR(samples[3].nodes_mm[1].x(), -70.0, 1e-3);  // 100 mm behind the tip
    EXPECT_EQ(sum.max_contact_force_N, 0.0);
    EXPECT_NEAR(sum.final_insertion_depth_mm, 30.0, 1e-9);
}

}  // namespace
}  // namespace scopekin::model
