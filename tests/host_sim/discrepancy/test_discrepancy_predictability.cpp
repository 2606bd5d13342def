// How far a recording's encoder decides the model's prediction (predictability.hpp), on made-up
// predictions whose answer is known: a branch that stays apart, a stiff response that does not,
// an event one run has a step earlier; and the recording moved and cut.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "host_sim/discrepancy/analysis.hpp"
#include "host_sim/discrepancy/predictability.hpp"

namespace scopekin::discrepancy {
namespace {

/// A 20 s recording: the hand advances 20 -> 120 mm (1 kHz encoder), the handle force measured
/// every 33 ms, the tip's region labelled sigmoid from 0 s and descending from 15 s.
MeasuredRecording twenty_second_advance() {
    MeasuredRecording data;
    data.source = "test";
    for (int i = 0; i <= 20000; ++i)
        data.drive.push_back({i / 1000.0, 20.0 + 5.0 * i / 1000.0, 0.001 * i / 1000.0});
    MeasuredSeries force;
    force.id = OutputId::handle_force;
    force.components = 1;
    for (int i = 0; 0.033 * i <= 20.0; ++i) {
        force.time_s.push_back(0.033 * i);
        force.value.emplace_back(1.0, 0.0, 0.0);
    }
    data.outputs.push_back(std::move(force));
    data.region_time_s = {0.0, 15.0};
    data.region = {"sigmoid", "descending"};
    data.start_s = 0.0;
    data.end_s = 20.0;
    data.duration_s = 20.0;
    data.initial_insertion_mm = 20.0;
    return data;
}

/// A prediction of the handle force: `value(t)` at every sample.
template <typename F>
ModelPrediction predicted(const MeasuredRecording& data, F value) {
    ModelPrediction p;
    p.ok = true;
    p.outputs.resize(1);
    for (double t : data.outputs[0].time_s)
        p.outputs[0].emplace_back(value(t), 0.0, 0.0);
    return p;
}

const std::vector<double> kNoise{0.02};  // N, the handle force sensor's
const std::vector<bool> kCounted{true};  // the model leaves the handle force beyond its noise

TEST(DiscrepancyPredictability, RunsThatNeverPartLeaveTheWholeRecordingPredictable) {
    const MeasuredRecording data = twenty_second_advance();
    const ModelPrediction a = predicted(data, [](double t) { return 10.0 + t; });
    EXPECT_FALSE(predictable_until(data, a, a, kNoise, kCounted).has_value());
}

TEST(DiscrepancyPredictability, AStiffResponseAFewNoiseSDsApartIsNotABranch) {
    // A locked scope: 0.01 mm more insertion, 3 N/mm more force... 0.06 N = 3 SDs, throughout.
    const MeasuredRecording data = twenty_second_advance();
    const ModelPrediction a = predicted(data, [](double t) { return 10.0 + t; });
    const ModelPrediction b = predicted(data, [](double t) { return 10.06 + t; });
    EXPECT_FALSE(predictable_until(data, a, b, kNoise, kCounted).has_value());
}

TEST(DiscrepancyPredictability, AnEventOneStepEarlierIsASpikeNotABranch) {
    // One run slips 0.1 s before the other (a 3 N drop), then both are the same again.
    const MeasuredRecording data = twenty_second_advance();
    const ModelPrediction a = predicted(data, [](double t) { return t < 9.0 ? 30.0 : 27.0; });
    const ModelPrediction b = predicted(data, [](double t) { return t < 9.1 ? 30.0 : 27.0; });
    EXPECT_FALSE(predictable_until(data, a, b, kNoise, kCounted).has_value());
}

TEST(DiscrepancyPredictability, ABranchEndsThePredictablePartWhereTheRunsLastAgreed) {
    // From 12 s one run slips in a sawtooth around 15 N, the other stays locked near 50 N; before,
    // they agree to 0.01 N (half a noise SD).
    const MeasuredRecording data = twenty_second_advance();
    const ModelPrediction a = predicted(data, [](double t) { return t < 12.0 ? 40.0 : 50.0; });
    const ModelPrediction b =
        predicted(data, [](double t) { return t < 12.0 ? 40.01 : 15.0 + 5.0 * std::fmod(t, 1.0); });
    const std::optional<double> until = predictable_until(data, a, b, kNoise, kCounted);
    ASSERT_TRUE(until.has_value());
    // The last sample before 12 s: 0.033 * 363 = 11.979 s.
    EXPECT_NEAR(*until, 11.979, 1e-9);
    // On an output the model already matches, a parting does not count.
    EXPECT_FALSE(predictable_until(data, a, b, kNoise, {false}).has_value());
}

TEST(DiscrepancyPredictability, TheDriveIsMovedWholeAndTheStartWithIt) {
    const MeasuredRecording data = twenty_second_advance();
    const MeasuredRecording moved = with_drive_offset(data, 0.005, -0.00005);
    ASSERT_EQ(moved.drive.size(), data.drive.size());
    for (std::size_t i = 0; i < data.drive.size(); i += 997) {
        EXPECT_DOUBLE_EQ(moved.drive[i].insertion_mm, data.drive[i].insertion_mm + 0.005);
        EXPECT_DOUBLE_EQ(moved.drive[i].roll_rad, data.drive[i].roll_rad - 0.00005);
        EXPECT_EQ(moved.drive[i].time_s, data.drive[i].time_s);
    }
    EXPECT_DOUBLE_EQ(moved.initial_insertion_mm, 20.005);
    EXPECT_EQ(moved.outputs[0].value, data.outputs[0].value);
}

TEST(DiscrepancyPredictability, TheCutRecordingEndsAtItsLastSampleBeforeTheCut) {
    MeasuredRecording data = twenty_second_advance();
    data.fit_spans_s = {{3.0, 8.0}};
    const MeasuredRecording cut = truncated_at(data, 14.5);
    EXPECT_DOUBLE_EQ(cut.end_s, 14.5);
    EXPECT_DOUBLE_EQ(cut.duration_s, 14.5);
    EXPECT_DOUBLE_EQ(cut.drive.back().insertion_mm, 20.0 + 5.0 * 14.5);
    ASSERT_EQ(cut.outputs.size(), 1U);
    EXPECT_LE(cut.outputs[0].time_s.back(), 14.5);
    EXPECT_GT(cut.outputs[0].time_s.back(), 14.5 - 0.033);
    EXPECT_EQ(cut.outputs[0].time_s.size(), cut.outputs[0].value.size());
    EXPECT_EQ(cut.region, std::vector<std::string>{"sigmoid"});
    EXPECT_TRUE(cut.fit_spans_s.empty());
    // Its blocks are cut anew over what is left: block 9 ends at 14.5 s.
    EXPECT_EQ(block_of(cut, 14.4), 9);
}

TEST(DiscrepancyPredictability, TooShortAPartIsRefusedSayingWhatIsNeeded) {
    const MeasuredRecording data = twenty_second_advance();
    try {
        (void)truncated_at(data, 11.0);
        FAIL() << "expected DiscrepancyInputError";
    } catch (const DiscrepancyInputError& e) {
        EXPECT_NE(std::string(e.what()).find("at least 12"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace scopekin::discrepancy
