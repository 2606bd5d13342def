// Scenario files with a virtual patient ("patient": {"seed": N} or {"file": ...}): the colon, the
// region properties, the friction and the scope's EI profile come from the patient; a patient
// with "colon", "colon_regions" or a friction coefficient is refused with the path; and a short
// run through a drawn patient completes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "model/model_error.hpp"
#include "model/patient/patient.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"
#include "model_test_support.hpp"

namespace scopekin::model {
namespace {

using testing::expect_model_error;

nlohmann::json with_patient(const nlohmann::json& patient) {
    nlohmann::json doc = nlohmann::json::parse(R"({
    "scope": {"model": "cf_q160l"},
    "initial_insertion_mm": 20,
    "procedure": [{"action": "advance", "start_s": 0, "end_s": 3, "speed_mm_per_s": 25}]
  })");
    doc["patient"] = patient;
    return doc;
}

TEST(PatientScenario, SeedGivesThePatientsColonFrictionAndScope) {
    const Scenario s = read_scenario(with_patient({{"seed", 3}}), "s.json");
    const PatientSpec p = draw_patient(3);
    ASSERT_TRUE(s.patient.has_value());
    EXPECT_EQ(patient_to_json(*s.patient).dump(), patient_to_json(p).dump());
    ASSERT_TRUE(s.colon.has_value());
    EXPECT_NEAR(s.colon->length_mm(), p.total_length_mm(), 1e-6 * p.total_length_mm());
    EXPECT_EQ(s.settings.contact.friction_coefficient, p.friction_coefficient);
    EXPECT_NEAR(s.colon_properties[1].young_modulus_kPa, 360.0 * p.wall_modulus_factor, 1e-9);
    // The scope: one ei_profile with the patient's factor at tip and handle.
    ASSERT_EQ(s.effects.size(), 1U);
    EXPECT_EQ(s.effects[0]->name(), "ei_profile");
    EXPECT_EQ(s.effects[0]->parameters()["tip_factor"].get<double>(), p.ei_factor);
    EXPECT_EQ(s.effects[0]->parameters()["handle_factor"].get<double>(), p.ei_factor);
    // A world model (scopekin discrepancy) makes the same effect again in scene_effects.
    const Scenario m = read_world_model(with_patient({{"seed", 3}}), "m.json");
    EXPECT_TRUE(m.effects.empty());
    ASSERT_EQ(scene_effects(m).size(), 1U);
    EXPECT_EQ(scene_effects(m)[0]->name(), "ei_profile");
}

TEST(PatientScenario, FileIsReadRelativeToTheScenario) {
    const auto dir = std::filesystem::temp_directory_path() / "scopekin_patient_scenario";
    std::filesystem::create_directories(dir);
    {
        std::ofstream f(dir / "p.json");
        f << patient_to_json(draw_patient(9)).dump(2);
    }
    const Scenario s = read_scenario(with_patient({{"file", "p.json"}}), (dir / "s.json").string());
    ASSERT_TRUE(s.patient.has_value());
    EXPECT_EQ(s.patient->seed, 9U);
    expect_model_error(
        [&] {
            (void)read_scenario(with_patient({{"file", "none.json"}}), (dir / "s.json").string());
        },
        "s.json: patient.file: ");
    std::filesystem::remove_all(dir);
}

TEST(PatientScenario, ConflictsAndBadKeysRefusedWithThePath) {
    nlohmann::json both = with_patient({{"seed", 1}});
    both["colon"] = {{"bundled", "default"}};
    expect_model_error([&] { (void)read_scenario(both, "s.json"); },
                       "s.json: patient: a scenario takes either 'patient'");
    nlohmann::json regions = with_patient({{"seed", 1}});
    regions["colon_regions"] = nlohmann::json::object();
    expect_model_error([&] { (void)read_scenario(regions, "s.json"); }, "s.json: colon_regions: ");
    nlohmann::json friction = with_patient({{"seed", 1}});
    friction["solver"] = {{"contact", {{"friction_coefficient", 0.3}}}};
    expect_model_error([&] { (void)read_scenario(friction, "s.json"); },
                       "s.json: solver.contact.friction_coefficient: the patient gives");
    nlohmann::json profile = with_patient({{"seed", 1}});
    profile["truth_effects"] = {{{"name", "ei_profile"}}};
    expect_model_error([&] { (void)read_scenario(profile, "s.json"); }, "truth_effects[0].name");
    expect_model_error(
        [&] {
            (void)read_scenario(with_patient({{"seed", 1}, {"file", "p.json"}}), "s.json");
        },
        "s.json: patient: give exactly one of 'seed'");
    expect_model_error(
        [&] { (void)read_scenario(with_patient(nlohmann::json::object()), "s.json"); },
        "s.json: patient: give exactly one of 'seed'");
    expect_model_error(
        [&] {
            (void)read_scenario(with_patient({{"seed", -1}}), "s.json");
        },
        "s.json: patient.seed: expected a whole number");
    expect_model_error(
        [&] {
            (void)read_scenario(with_patient({{"seed", 1e30}}), "s.json");
        },
        "s.json: patient.seed: expected a whole number");
    expect_model_error(
        [&] {
            (void)read_scenario(with_patient({{"seed", "x"}}), "s.json");
        },
        "s.json: patient.seed: expected a whole number");
    expect_model_error([&] { (void)read_scenario(with_patient(7), "s.json"); }, "s.json: patient");
}

TEST(PatientScenario, ShortRunThroughADrawnPatientCompletes) {
    // 300 steps of 10 ms: 20 mm in, advanced 75 mm at 25 mm/s into the rectum of patient 3.
    const Scenario s = read_scenario(with_patient({{"seed", 3}}), "s.json");
    auto world = build_world(s);
    SimulationCallbacks callbacks;
    const SimulationSummary sum = run_simulation(*world, s, callbacks);
    ASSERT_TRUE(sum.complete) << sum.message;
    EXPECT_EQ(sum.steps, 300U);
    EXPECT_NEAR(sum.final_insertion_depth_mm, 95.0, 1e-6);
}

}  // namespace
}  // namespace scopekin::model
