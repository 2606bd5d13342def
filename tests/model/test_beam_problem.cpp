// Beam problem files (model/io): strict reading with errors that name the field, and a file
// that reproduces a published benchmark end to end.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "model/io/beam_problem.hpp"
#include "model/model_error.hpp"

namespace scopekin::model::io {
namespace {

nlohmann::json valid_problem() {
    return nlohmann::json::parse(R"({
    "beam": {"straight": {"length_mm": 1000, "elements": 20},
             "section": {"EA_N": 1e8, "EI_Nmm2": 1e6, "GJ_Nmm2": 1e6, "kappa_GA_N": 1e8}},
    "loads": [{"node": 20, "force_N": [0, -10, 0]}],
    "supports": [{"node": 0}]
  })");
}

/// Expects ModelError whose message contains `fragment`.
void expect_error(const nlohmann::json& doc, const std::string& fragment) {
    try {
        read_beam_problem(doc, "problem.json");
        ADD_FAILURE() << "no error; expected one mentioning '" << fragment << "'";
    } catch (const ModelError& e) {
        EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
}

TEST(BeamProblem, MattiassonFileReproducesPublishedTip) {
    BeamProblem p = read_beam_problem(valid_problem(), "problem.json");
    const StaticReport report = solve_static(p.beam, p.loads, p.supports, p.settings);
    ASSERT_TRUE(report.converged) << report.message;
    // Mattiasson (1981), P L^2 / EI = 10: w/L = 0.81061, u/L = 0.55500.
    EXPECT_NEAR(-p.beam.position(20).y() / 1000.0, 0.81061, 0.005);
    EXPECT_NEAR((1000.0 - p.beam.position(20).x()) / 1000.0, 0.55500, 0.005);
    EXPECT_EQ(p.output_nodes.size(), 21u);
}

TEST(BeamProblem, UnknownKeyIsNamedWithItsPath) {
    nlohmann::json doc = valid_problem();
    doc["beam"]["sectoin"] = "cf_q160l";
    expect_error(doc, "problem.json: beam.sectoin: unknown key");
    doc = valid_problem();
    doc["supports"][0]["fixx"] = true;
    expect_error(doc, "supports[0].fixx: unknown key");
    doc = valid_problem();
    doc["colour"] = "red";
    expect_error(doc, "problem.json: colour: unknown key");
}

TEST(BeamProblem, NodeChecksNameTheFile) {
    // Found by fuzz.scenario: the node checks run after reading and named the field only.
    nlohmann::json doc = valid_problem();
    doc["loads"][0]["node"] = 21;
    expect_error(doc, "problem.json: loads[0].node: 21 is out of range (beam has 21 nodes)");
    doc = valid_problem();
    doc["supports"][0]["node"] = 21;
    expect_error(doc, "problem.json: supports[0].node: 21 is out of range");
    doc = valid_problem();
    doc["supports"].push_back({{"node", 0}});
    expect_error(doc, "problem.json: supports[1].node: node 0 is supported twice");
}

TEST(BeamProblem, BadValuesAreNamed) {
    nlohmann::json doc = valid_problem();
    doc["beam"]["section"]["EI_Nmm2"] = -5;
    expect_error(doc, "beam.section.EI_Nmm2: -5 must be > 0");
    doc = valid_problem();
    doc["beam"]["section"]["EA_N"] = "stiff";
    expect_error(doc, "beam.section.EA_N: expected a number");
    doc = valid_problem();
    doc["beam"]["straight"]["elements"] = 0;
    expect_error(doc, "beam.straight.elements");
    doc = valid_problem();
    doc["loads"][0]["node"] = 21;
    expect_error(doc, "loads[0].node: 21 is out of range");
    doc = valid_problem();
    doc["loads"][0]["force_N"] = {0, 1};
    expect_error(doc, "loads[0].force_N: expected an array of 3 numbers");
    doc = valid_problem();
    doc["supports"][0]["node"] = -1;
    expect_error(doc, "supports[0].node: expected a non-negative integer");
    doc = valid_problem();
    doc["beam"]["section"] = "cf_q999";
    expect_error(doc, "unknown section name 'cf_q999'");
    doc = valid_problem();
    doc["beam"]["nodes_mm"] = {{0, 0, 0}, {0, 0, 0}};
    expect_error(doc, "give exactly one of nodes_mm or straight");
}

TEST(BeamProblem, ZeroLengthElementFromNodesIsNamed) {
    nlohmann::json doc = valid_problem();
    doc["beam"].erase("straight");
    doc["beam"]["nodes_mm"] = {{0, 0, 0}, {10, 0, 0}, {10, 0, 0}};
    doc["loads"] = nlohmann::json::array();
    expect_error(doc, "element 1: length 0");
}

TEST(BeamProblem, PrescribedRotationFromFile) {
    // A slender beam whose free end is turned by 90 deg about z (translations free) bends into a
    // quarter circle: tip at L (sin t / t, (1 - cos t) / t) with t = pi/2 (inextensible elastica).
    nlohmann::json doc = valid_problem();
    doc["loads"] = nlohmann::json::array();
    doc["supports"].push_back({{"node", 20},
                               {"fix_x", false},
                               {"fix_y", false},
                               {"fix_z", false},
                               {"target_rotation", {{"axis", {0, 0, 1}}, {"angle_deg", 90}}}});
    BeamProblem p = read_beam_problem(doc, "problem.json");
    const StaticReport report = solve_static(p.beam, p.loads, p.supports, p.settings);
    ASSERT_TRUE(report.converged) << report.message;
    const double t = M_PI / 2.0;
    EXPECT_NEAR(p.beam.position(20).x(), 1000.0 * std::sin(t) / t, 1.0);
    EXPECT_NEAR(p.beam.position(20).y(), 1000.0 * (1.0 - std::cos(t)) / t, 1.0);
}

}  // namespace
}  // namespace scopekin::model::io
