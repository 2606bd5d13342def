// The reduced model's builder (model/reduction) and the firmware's reduced step in double
// (firmware/kinetics/reduced_kinetics.hpp). Expected numbers: the Timoshenko cantilever closed
// form, and the training run's own state (the reduction's defining property: on the training
// procedure the reduced model has no deviation to add).
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "model/colon/bundled_colons.hpp"
#include "model/model_error.hpp"
#include "model/reduction/reduced_model.hpp"
#include "model/reduction/reduced_model_json.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/world/world.hpp"

namespace scopekin::model {
namespace {

Scenario short_training() {
    const char* text = R"({
    "description": "short training: 20 -> 200 mm at 25 mm/s",
    "colon": {"bundled": "default"},
    "scope": {"model": "cf_q160l", "length_mm": 1700, "elements": 170},
    "gravity_mm_per_s2": [0, 0, -9810],
    "initial_insertion_mm": 20,
    "solver": {"time_step_s": 0.01},
    "procedure": [{"action": "advance", "start_s": 0, "end_s": 7.4, "speed_mm_per_s": 25}],
    "outputs": {"sample_rate_Hz": 30}
  })";
    return read_scenario(nlohmann::json::parse(text), "short_training");
}

ReductionSettings short_settings() {
    ReductionSettings s;
    s.source = "short_settings";
    s.stations = 4;
    s.station_spacing_mm = 50.0;
    s.compliance_every = 4;
    ReductionSegmentSpec advance;
    advance.scenario = short_training();
    advance.direction = 1;
    advance.depth_from_mm = 30.0;
    advance.depth_to_mm = 190.0;
    advance.step_mm = 10.0;
    s.segments.push_back(advance);
    return s;
}

// A straight scope in a straight, wide, fixed tube touches nothing: the tip's compliance across
// the axis is the cantilever's L^3 / (3 EI) + L / (kappa G A) (free length L past the anus,
// where the hand holds it), plus the wall compliance and the colon's own at that point.
TEST(StationProbe, StraightScopeTipComplianceIsTheCantilever) {
    const ColonTube tube = straight_tube(600.0, 20.0, ColonRegion::rectum, cf_q160l::kRadius_mm);
    WorldSettings settings;
    settings.gravity_mm_per_s2.setZero();
    settings.initial_insertion_mm = 300.0;
    ScopeSpec scope;
    scope.length_mm = 600.0;
    scope.elements = 60;
    scope.section = cf_q160l::section();
    World world(scope, tube, default_colon_properties(), settings);
    const std::size_t tip = world.scope_node_count() - 1;
    const StationCompliance probe = world.probe_stations({tip});
    ASSERT_TRUE(probe.stations[0].inside);
    EXPECT_NEAR(probe.stations[0].path_mm, 300.0, 1e-9);
    EXPECT_NEAR(probe.stations[0].gap_mm, 20.0 - cf_q160l::kRadius_mm, 1e-9);
    const double length = 300.0;
    const double bending = scope.section.bending_stiffness_y_Nmm2;
    const double expected_scope =
        length * length * length / (3.0 * bending) + length / scope.section.shear_stiffness_y_N;
    const ColonCompliance colon(build_colon_structure(tube, default_colon_properties()));
    const StationProbe& p = probe.stations[0];
    const Eigen::Matrix3d colon_block =
        p.frame.transpose() *
        colon.point_block(p.colon_segment, p.colon_weight, p.colon_segment, p.colon_weight) *
        p.frame;
    const double wall = settings.contact.wall_compliance_mm_per_N;
    // n and s are across the axis (n towards the centerline), t along it.
    EXPECT_NEAR(probe.compliance_mm_per_N(0, 0) - wall - colon_block(0, 0), expected_scope,
                1e-6 * expected_scope);
    EXPECT_NEAR(probe.compliance_mm_per_N(2, 2) - wall - colon_block(2, 2), expected_scope,
                1e-6 * expected_scope);
    const double axial = length / scope.section.axial_stiffness_N;
    EXPECT_NEAR(probe.compliance_mm_per_N(1, 1) - wall - colon_block(1, 1), axial, 1e-6 * axial);
}

TEST(ReducedModel, RejectsStationsOffTheNodes) {
    ReductionSettings s = short_settings();
    s.station_spacing_mm = 55.0;  // elements are 10 mm
    EXPECT_THROW(build_reduced_model(s), ModelError);
}

TEST(ReducedModel, RejectsTrainingThatEndsBeforeTheLastKnot) {
    ReductionSettings s = short_settings();
    s.segments[0].depth_to_mm = 390.0;
    EXPECT_THROW(build_reduced_model(s), ModelError);
}

TEST(ReducedModel, RejectsBadSegments) {
    ReductionSettings withdraw_first = short_settings();
    withdraw_first.segments[0].direction = -1;
    std::swap(withdraw_first.segments[0].depth_from_mm, withdraw_first.segments[0].depth_to_mm);
    EXPECT_THROW(withdraw_first.validate(), ModelError);
    ReductionSettings backwards = short_settings();
    backwards.segments[0].depth_to_mm = 10.0;
    EXPECT_THROW(backwards.validate(), ModelError);
    ReductionSettings ragged = short_settings();
    ragged.compliance_every = 3;  // 16 intervals
    EXPECT_THROW(ragged.validate(), ModelError);
    ReductionSettings off_step = short_settings();
    off_step.segments[0].depth_to_mm = 185.0;
    EXPECT_THROW(off_step.validate(), ModelError);
}

// On the training procedure, at the knots, the reduced step reproduces the training (full-order)
// state: the station friction puts the training force on its cone where the stretch slid and
// inside it where it stuck, the training slip follows the friction force, and stations whose
// resultant no cone holds follow the training (reduced_kinetics.hpp). Expected: the training
// run's own tip path and station forces.
TEST(ReducedModel, ReproducesItsTrainingRunAtTheKnots) {
    const ReductionSettings s = short_settings();
    const ReducedModelData data = build_reduced_model(s);
    ASSERT_EQ(data.knots.size(), 17U);
    ASSERT_EQ(data.compliances.size(), 5U);
    static kinetics::ReducedState<double, 4> state;
    contact::GaussSeidelSettings<double> gs;
    gs.mode = contact::SweepMode::until_converged;
    gs.tolerance = 1e-10;
    gs.max_sweeps = 50;
    for (std::size_t g = 0; g < data.knots.size(); ++g) {
        const double depth = 30.0 + 10.0 * static_cast<double>(g);
        const auto report = kinetics::reduced_step(data, depth, 0.4, state, gs);  // 25 mm/s
        EXPECT_EQ(report.contact.status, contact::ContactSolveStatus::converged);
        EXPECT_NEAR(state.tip_path_mm, data.value(g, kinetics::kStationPath), 1e-6)
            << "depth " << depth;
        for (std::size_t j = 0; j < state.active_stations; ++j)
            for (std::size_t c = 0; c < 3; ++c)
                EXPECT_NEAR(
                    state.force_N[j][c],
                    data.value(g, j * kinetics::kStationValueCount + kinetics::kStationForceN + c),
                    1e-6)
                    << "depth " << depth << " station " << j;
    }
    // 190 mm inserted: all four stations (0 .. 150 mm from the tip) are inside.
    EXPECT_EQ(state.active_stations, 4U);
    EXPECT_NEAR(state.tip_path_mm, 190.0, 15.0);
}

// The double data written for the accuracy tests reads back bit for bit (header and every value),
// and a file made for another spec, a short record or a non-number is refused by name.
TEST(ReducedModelJson, RoundTripsExactlyAndRefusesWhatDoesNotFit) {
    const ReductionSettings s = short_settings();
    ReducedModelData data = build_reduced_model(s);
    data.knots[3][1] = 0.1 + 0.2;  // not a short decimal: must still read back to the same bits
    const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                      ("scopekin_reduced_json_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const auto write = [&](const std::string& name, const ReducedModelData& d) {
        std::ofstream out(dir / name);
        write_reduced_model_json(d, out);
        return (dir / name).string();
    };
    const ReducedModelData back = read_reduced_model_json(write("good.json", data), s);
    EXPECT_EQ(back.knots, data.knots);
    EXPECT_EQ(back.compliances, data.compliances);
    EXPECT_EQ(back.head.stations, data.head.stations);
    EXPECT_EQ(back.head.friction, data.head.friction);
    ASSERT_EQ(back.head.segment_count, 1U);
    EXPECT_EQ(back.head.segments[0].knots, data.head.segments[0].knots);
    EXPECT_EQ(back.head.segments[0].key_start, data.head.segments[0].key_start);
    EXPECT_EQ(back.head.segments[0].key_step, data.head.segments[0].key_step);

    ReductionSettings other = s;
    other.station_spacing_mm = 40.0;
    EXPECT_THROW((void)read_reduced_model_json(dir / "good.json", other), ModelError);
    ReducedModelData short_record = data;
    short_record.knots[2].pop_back();
    EXPECT_THROW((void)read_reduced_model_json(write("short.json", short_record), s), ModelError);
    ReducedModelData not_finite = data;
    not_finite.compliances[1][0] = std::nan("");  // written as null
    EXPECT_THROW((void)read_reduced_model_json(write("nan.json", not_finite), s), ModelError);
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace scopekin::model
