// The discrepancy workflow's data handling (host_sim/discrepancy/): what it takes from a
// recording and refuses, the noise estimate, the blocked hold-out and the phases. Expected
// numbers are independent of the code: a known noise SD, hand-made recordings. And its model
// runs: windows restarted from saved states, and a recording's drive stepped by the same loop
// as a procedure.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "host_sim/discrepancy/analysis.hpp"
#include "host_sim/discrepancy/evaluator.hpp"
#include "host_sim/discrepancy/fit_windows.hpp"
#include "host_sim/discrepancy/measured_recording.hpp"
#include "host_sim/discrepancy/model_run.hpp"
#include "host_sim/discrepancy/model_spec.hpp"
#include "host_sim/discrepancy/robust_objective.hpp"
#include "model/scenario/procedure.hpp"
#include "model/scenario/simulation.hpp"

namespace scopekin::discrepancy {
namespace {

/// A recording of `seconds`: the encoder at 1 kHz advancing 20 mm/s from 20 mm (a roll of
/// 0.1 rad/s from 10 s), the EM tip at every 33rd ms on a line plus N(0, sd) per axis.
recording::Recording make_recording(double seconds, double em_sd_mm, unsigned seed = 3) {
    std::mt19937 engine(seed);
    std::normal_distribution<double> noise(0.0, em_sd_mm);
    recording::Recording rec;
    const auto ms = static_cast<std::int64_t>(seconds * 1000.0);
    for (std::int64_t t = 1; t <= ms; ++t) {
        recording::RecordingRow row;
        row.time_us = t * 1000;
        const double s = static_cast<double>(t) * 1e-3;
        row.insertion_roll =
            recording::InsertionRollCells{20.0 + 20.0 * s, s > 10.0 ? 0.1 * (s - 10.0) : 0.0};
        row.handle = recording::ForceTorqueCells{1.0, 0.0};
        if (t % 33 == 0) {
            recording::EmPoseCells pose;
            pose.position_mm = {20.0 * s + noise(engine), 5.0 + noise(engine),
                                -3.0 + noise(engine)};
            row.em[static_cast<std::size_t>(recording::EmSlot::tip)] = pose;
        }
        rec.rows.push_back(row);
    }
    return rec;
}

std::string refusal(const recording::Recording& rec) {
    try {
        (void)extract_measured_recording(rec, "r.csv");
    } catch (const DiscrepancyInputError& e) {
        return e.what();
    }
    return "";
}

TEST(DiscrepancyMeasuredRecording, TakesTheDriveAndTheOutputsItHas) {
    const MeasuredRecording d = extract_measured_recording(make_recording(20.0, 0.5), "r.csv");
    EXPECT_EQ(d.drive.size(), 20000u);
    EXPECT_DOUBLE_EQ(d.start_s, 0.001);
    EXPECT_DOUBLE_EQ(d.initial_insertion_mm, 20.02);
    EXPECT_NEAR(d.insertion_at(10.0), 220.0, 1e-9);
    EXPECT_NEAR(d.roll_at(12.0), 0.2, 1e-9);
    // The tip's EM position (606 samples) and the handle force and torque, thinned to every 33 ms.
    ASSERT_EQ(d.outputs.size(), 3u);
    EXPECT_EQ(d.outputs[0].id, OutputId::tip_position);
    EXPECT_EQ(d.outputs[0].time_s.size(), 606u);
    EXPECT_EQ(d.outputs[1].id, OutputId::handle_force);
    EXPECT_EQ(d.outputs[1].time_s.size(), 607u);
}

TEST(DiscrepancyMeasuredRecording, RefusesWhatCannotDriveOrBeCompared) {
    recording::Recording no_encoder = make_recording(20.0, 0.5);
    for (auto& row : no_encoder.rows)
        row.insertion_roll.reset();
    EXPECT_NE(refusal(no_encoder).find("no handle motion"), std::string::npos)
        << refusal(no_encoder);

    recording::Recording metres = make_recording(20.0, 0.5);
    for (auto& row : metres.rows)
        row.insertion_roll->insertion_mm /= 1000.0;
    EXPECT_NE(refusal(metres).find("metres instead of millimetres"), std::string::npos)
        << refusal(metres);

    recording::Recording degrees = make_recording(20.0, 0.5);
    for (auto& row : degrees.rows)
        row.insertion_roll->roll_rad *= 180.0 / M_PI * 10.0;
    EXPECT_NE(refusal(degrees).find("degrees instead of radians"), std::string::npos)
        << refusal(degrees);

    EXPECT_NE(refusal(make_recording(10.0, 0.5)).find("too short to hold data out"),
              std::string::npos);

    recording::Recording no_outputs = make_recording(20.0, 0.5);
    for (auto& row : no_outputs.rows)
        row.em = {};
    EXPECT_NE(refusal(no_outputs).find("no measured output"), std::string::npos)
        << refusal(no_outputs);

    recording::Recording millinewtons = make_recording(20.0, 0.5);
    for (auto& row : millinewtons.rows)
        row.handle->force_N = 1000.0;
    EXPECT_NE(refusal(millinewtons).find("needs newtons"), std::string::npos)
        << refusal(millinewtons);
}

TEST(DiscrepancyAnalysis, NoiseEstimateRecoversAKnownSd) {
    // Three axes of N(0, 0.5 mm) on a straight line: the combined SD is 0.5 sqrt(3) = 0.866 mm.
    const MeasuredRecording d = extract_measured_recording(make_recording(60.0, 0.5, 7), "r.csv");
    const std::vector<double> sigma = estimate_noise(d);
    EXPECT_NEAR(sigma[0], 0.5 * std::sqrt(3.0), 0.05 * 0.866);
    // A constant handle force has no noise to estimate: not assessed.
    EXPECT_EQ(sigma[1], 0.0);
    EXPECT_FALSE(assessable(sigma, 1));
}

TEST(DiscrepancyAnalysis, AHandleForceThatChangesFastHasItsNoiseEstimatedAtTheSensorsRate) {
    // The handle at 1 kHz: a scope sticking and slipping, 10 N at 3 Hz, plus N(0, 0.02 N) per
    // sample. Over the 33 ms the outputs are compared at, its second difference is
    // 10 (2 pi 3 0.033)^2 = 3.9 N at the peaks, 200 times the noise; over 1 ms, 0.0036 N.
    recording::Recording rec = make_recording(30.0, 0.5, 11);
    std::mt19937 engine(5);
    std::normal_distribution<double> noise(0.0, 0.02);
    constexpr double kTwoPi = 6.283185307179586;
    for (recording::RecordingRow& row : rec.rows) {
        const double t = static_cast<double>(row.time_us) * 1e-6;
        row.handle = recording::ForceTorqueCells{
            20.0 + 10.0 * std::sin(kTwoPi * 3.0 * t) + noise(engine), 0.0};
    }
    const MeasuredRecording d = extract_measured_recording(rec, "r.csv");
    std::size_t handle = d.outputs.size();
    for (std::size_t o = 0; o < d.outputs.size(); ++o)
        if (d.outputs[o].id == OutputId::handle_force) handle = o;
    ASSERT_LT(handle, d.outputs.size());
    // Premise: compared every 33 ms (the EM tracker's rate), not at 1 kHz.
    ASSERT_NEAR(static_cast<double>(d.outputs[handle].value.size()), 30.0 / 0.033, 2.0);
    EXPECT_NEAR(estimate_noise(d)[handle], 0.02, 0.1 * 0.02);
}

TEST(DiscrepancyAnalysis, BlocksPhasesAndResiduals) {
    const MeasuredRecording d = extract_measured_recording(make_recording(20.0, 0.5), "r.csv");
    // 20 s in 10 blocks of ~2 s; blocks 1, 4 and 7 are held out.
    EXPECT_EQ(block_of(d, 0.5), 0);
    EXPECT_EQ(block_of(d, 3.0), 1);
    EXPECT_EQ(block_of(d, 19.99), 9);
    EXPECT_TRUE(in_set(d, 3.0, SampleSet::held_out));
    EXPECT_TRUE(in_set(d, 9.5, SampleSet::held_out));
    EXPECT_TRUE(in_set(d, 5.0, SampleSet::training));
    EXPECT_EQ(phase_at(d, 5.0), "push");
    EXPECT_EQ(phase_at(d, 15.0), "twist");
    // A model that predicts the measurement exactly: zero error.
    ModelPrediction exact;
    exact.ok = true;
    for (const MeasuredSeries& m : d.outputs)
        exact.outputs.push_back(m.value);
    EXPECT_EQ(rms_error(d, exact, 0, SampleSet::all), 0.0);
    // One 3 mm off everywhere: RMS 3 mm; in units of a 0.866 mm noise over both sets, 3/0.866.
    ModelPrediction shifted = exact;
    for (auto& v : shifted.outputs[0])
        v.x() += 3.0;
    EXPECT_NEAR(rms_error(d, shifted, 0, SampleSet::held_out), 3.0, 1e-12);
    const std::vector<double> sigma{0.866, 0.0, 0.0};
    EXPECT_NEAR(normalised_residuals(d, shifted, sigma, SampleSet::training).squaredNorm(),
                std::pow(3.0 / 0.866, 2), 1e-9);
}

// The fits' objective caps a training block that stands out (robust_objective.hpp): a model off
// by 3 mm in one training block only (an event shifted in time) and exact elsewhere costs, plain,
// (3/0.866)^2 times that block's share of the training samples; capped, ten times the block's
// noise floor (the same share). Off by 3 mm everywhere, no block stands out: nothing is capped.
TEST(DiscrepancyAnalysis, AnOutlierBlockIsCappedAndASmoothMisfitIsNot) {
    const MeasuredRecording d = extract_measured_recording(make_recording(20.0, 0.5), "r.csv");
    const std::vector<double> sigma{0.866, 0.0, 0.0};
    const BlockRows rows = block_rows(d, sigma, SampleSet::training);
    ModelPrediction exact;
    exact.ok = true;
    for (const MeasuredSeries& m : d.outputs)
        exact.outputs.push_back(m.value);
    // Seven training blocks (0, 2, 3, 5, 6, 8, 9), each about a seventh of the samples.
    double floor_sum = 0.0;
    for (int b = 0; b < kBlocks; ++b) {
        EXPECT_EQ(rows.noise_floor[static_cast<std::size_t>(b)] > 0.0, !is_held_out_block(b)) << b;
        floor_sum += rows.noise_floor[static_cast<std::size_t>(b)];
    }
    EXPECT_NEAR(floor_sum, 1.0, 1e-12);
    ModelPrediction event = exact;
    const MeasuredSeries& tip = d.outputs[0];
    for (std::size_t i = 0; i < tip.time_s.size(); ++i)
        if (block_of(d, tip.time_s[i]) == 5) event.outputs[0][i].x() += 3.0;
    const Eigen::VectorXd plain = normalised_residuals(d, event, sigma, SampleSet::training);
    const double block5_share = rows.noise_floor[5];
    EXPECT_NEAR(plain.squaredNorm(), std::pow(3.0 / 0.866, 2) * block5_share, 1e-9);
    EXPECT_NEAR(cap_outlier_blocks(rows, plain).squaredNorm(), kBlockCapOverNoise * block5_share,
                1e-9);
    // The same misfit everywhere: no block stands out, nothing capped.
    ModelPrediction smooth = exact;
    for (auto& v : smooth.outputs[0])
        v.x() += 3.0;
    const Eigen::VectorXd everywhere = normalised_residuals(d, smooth, sigma, SampleSet::training);
    EXPECT_NEAR(cap_outlier_blocks(rows, everywhere).squaredNorm(), everywhere.squaredNorm(),
                1e-12);
    // An exact model: nothing to cap either.
    EXPECT_EQ(cap_outlier_blocks(rows, normalised_residuals(d, exact, sigma, SampleSet::training))
                  .squaredNorm(),
              0.0);
}

// On windows the screening's grid is costed on four of the seven training blocks (0, 3, 6, 9),
// spread over the recording, none held out; a grid start then runs the other windows. The cost
// there is the capped cost of those blocks alone: the other blocks' rows, unrun (NaN), count
// nothing and take no part in the median, and a block that stands out is capped as before.
TEST(DiscrepancyAnalysis, TheScreeningBlocksCostAloneWithTheirOwnCap) {
    std::vector<int> screening;
    for (int b = 0; b < kBlocks; ++b) {
        if (is_screening_block(b)) screening.push_back(b);
        EXPECT_FALSE(is_screening_block(b) && is_held_out_block(b)) << b;
        EXPECT_NE(window_in_scope(b, RunScope::fit_screening),
                  window_in_scope(b, RunScope::fit_after_screening))
            << b;
    }
    EXPECT_EQ(screening, (std::vector<int>{0, 3, 6, 9}));
    const MeasuredRecording d = extract_measured_recording(make_recording(20.0, 0.5), "r.csv");
    const std::vector<double> sigma{0.866, 0.0, 0.0};
    const BlockRows rows = block_rows(d, sigma, SampleSet::training);
    ModelPrediction run;  // exact in the screening blocks, unrun elsewhere
    run.ok = true;
    for (const MeasuredSeries& m : d.outputs)
        run.outputs.push_back(m.value);
    const MeasuredSeries& tip = d.outputs[0];
    for (std::size_t i = 0; i < tip.time_s.size(); ++i)
        if (!is_screening_block(block_of(d, tip.time_s[i])))
            run.outputs[0][i].x() = std::numeric_limits<double>::quiet_NaN();
    auto cost = [&](const ModelPrediction& p) {
        return capped_cost_on_blocks(rows, normalised_residuals(d, p, sigma, SampleSet::training),
                                     is_screening_block);
    };
    EXPECT_EQ(cost(run), 0.0);
    // 1 mm off in block 3 only: (1/0.866)^2 of its share, below its cap of ten noise floors.
    ModelPrediction small = run, large = run;
    for (std::size_t i = 0; i < tip.time_s.size(); ++i)
        if (block_of(d, tip.time_s[i]) == 3) {
            small.outputs[0][i].x() += 1.0;
            large.outputs[0][i].x() += 3.0;
        }
    EXPECT_NEAR(cost(small), std::pow(1.0 / 0.866, 2) * rows.noise_floor[3], 1e-9);
    // 3 mm off there, (3/0.866)^2 = 12 floors: capped at ten, the other screening blocks exact.
    EXPECT_NEAR(cost(large), kBlockCapOverNoise * rows.noise_floor[3], 1e-9);
}

// Windows: one per block where the hand moves most, the first part spin-up; none when the
// blocks fit the budget whole. A hand-made drive: 100 s holding at 50 mm except, 5 s into each
// 10 s block, 20 mm in at 10 mm/s and out again (5..9 s).
TEST(DiscrepancyFitWindows, OneWindowPerBlockAroundTheHandsMotion) {
    MeasuredRecording d;
    for (int k = 0; k <= 10000; ++k) {
        const double t = 0.01 * k;
        const double in_block = std::fmod(t, 10.0);
        const double advance = in_block < 5.0   ? 0.0
                               : in_block < 7.0 ? 10.0 * (in_block - 5.0)
                               : in_block < 9.0 ? 10.0 * (9.0 - in_block)
                                                : 0.0;
        d.drive.push_back({t, 50.0 + advance, 0.0});
    }
    d.start_s = 0.0;
    d.end_s = 100.0;
    d.duration_s = 100.0;
    d.initial_insertion_mm = 50.0;
    EXPECT_NEAR(hand_motion_mm(d, 0.0, 10.0), 40.0, 1e-9);  // 20 mm in, 20 mm out
    EXPECT_TRUE(choose_fit_windows(d, 100.0).empty());      // 10 s windows = the blocks: full runs
    const std::vector<RunWindow> w = choose_fit_windows(d, 40.0);
    ASSERT_EQ(w.size(), 10u);
    for (int b = 0; b < 10; ++b) {
        const RunWindow& x = w[static_cast<std::size_t>(b)];
        EXPECT_EQ(x.block, b);
        // 4 s windows: the one that holds all the motion is 5..9 s.
        EXPECT_NEAR(x.start_s, 10.0 * b + 5.0, 1e-9);
        EXPECT_NEAR(x.end_s, x.start_s + 4.0, 1e-9);
        EXPECT_NEAR(x.score_from_s, x.start_s + 2.0,
                    1e-9);  // spin-up: half of a window shorter than 6 s
    }
    // The fit sets keep the scored spans only.
    for (const RunWindow& x : w)
        d.fit_spans_s.emplace_back(x.score_from_s, x.end_s);
    EXPECT_TRUE(in_set(d, 8.0, SampleSet::fit_training));
    EXPECT_FALSE(in_set(d, 6.0, SampleSet::fit_training));  // spin-up
    EXPECT_FALSE(in_set(d, 9.5, SampleSet::fit_training));  // after the window
    EXPECT_TRUE(in_set(d, 18.0, SampleSet::fit_held_out));  // block 1
    EXPECT_FALSE(in_set(d, 18.0, SampleSet::fit_training));
    EXPECT_TRUE(in_set(d, 9.5, SampleSet::training));  // the plain sets are unchanged
}

// A recording of 10^8 s (one with a gap that long, read with the bound raised) places its
// windows with bounded work: at most kMaxWindowStarts candidate starts per block, spread over it,
// so the motion still wins.
TEST(DiscrepancyFitWindows, AVeryLongRecordingIsSearchedWithBoundedWork) {
    MeasuredRecording d;
    d.drive = {{0.0, 50.0, 0.0}, {13.0, 100.0, 0.0}, {1e8, 100.0, 0.0}};
    d.start_s = 0.0;
    d.end_s = 1e8;
    d.duration_s = 1e8;
    d.initial_insertion_mm = 50.0;
    const auto started = std::chrono::steady_clock::now();
    const std::vector<RunWindow> w = choose_fit_windows(d, 80.0);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    ASSERT_EQ(w.size(), 10u);
    // The only motion is in the first 13 s: block 0's window starts where it is (0 s).
    EXPECT_NEAR(w[0].start_s, 0.0, 1e-9);
    // 10 blocks x 4001 starts x 160 samples: 0.06 s here. Every 0.25 s instead, 4 x 10^7 starts
    // a block: about 10 minutes (6 s for 10^6 s).
    EXPECT_LT(seconds, 30.0);
}

// A window restarted from the full run's saved state, with the same model, steps through the
// same numbers: its outputs are the full run's, bit for bit (the fits' finite differences rely on
// it), and they are NaN outside the scored spans.
TEST(DiscrepancyFitWindows, WindowedRunOfTheModelAsGivenRepeatsTheFullRun) {
    const MeasuredRecording d = extract_measured_recording(make_recording(14.0, 0.5), "r.csv");
    const std::vector<RunWindow> windows = choose_fit_windows(d, 12.0);
    ASSERT_EQ(windows.size(), 10u);
    std::vector<model::World::State> states;
    const ModelSpec model = read_model_spec(default_model(), "default");
    const ModelPrediction full = predict(model, nlohmann::json::array(), d, {}, &windows, &states);
    ASSERT_TRUE(full.ok) << full.failure;
    const ModelPrediction part =
        predict_windows(model, nlohmann::json::array(), d, windows, states, {2, 5, 9});
    ASSERT_TRUE(part.ok) << part.failure;
    std::size_t compared = 0, outside = 0;
    for (std::size_t o = 0; o < d.outputs.size(); ++o)
        for (std::size_t i = 0; i < d.outputs[o].time_s.size(); ++i) {
            const double t = d.outputs[o].time_s[i];
            bool scored = false;
            for (std::size_t w : {2u, 5u, 9u})
                scored = scored || (t >= windows[w].score_from_s && t <= windows[w].end_s);
            if (scored) {
                EXPECT_EQ(part.outputs[o][i], full.outputs[o][i])
                    << "output " << o << " at " << t << " s";
                ++compared;
            } else {
                EXPECT_TRUE(std::isnan(part.outputs[o][i].x()));
                ++outside;
            }
        }
    EXPECT_GT(compared, 50u);
    EXPECT_GT(outside, compared);
}

/// Plays a procedure and keeps the commands it gave.
class LoggedPlayer final : public model::HandCommandSource {
public:
    explicit LoggedPlayer(model::ProcedurePlayer player) : player_(std::move(player)) {}
    model::HandleCommand command_for_step(std::size_t step, double t_s, double h_s,
                                          double depth_now_mm, double roll_now_rad) override {
        log.push_back(player_.command_for_step(step, t_s, h_s, depth_now_mm, roll_now_rad));
        return log.back();
    }
    std::vector<model::HandleCommand> log;

private:
    model::ProcedurePlayer player_;
};

// One stepping loop for procedures and recordings (model::run_simulation): the commands a
// procedure gave, replayed as a recording's encoder (RecordingDrive), step the world to the same
// world.csv rows, bit for bit.
TEST(DiscrepancyRecordingDrive, ReplaysAProcedureToTheSameWorldRows) {
    nlohmann::json doc = default_model();
    doc["initial_insertion_mm"] = 20.0;
    doc["outputs"] = {{"sample_rate_Hz", 100}, {"nodes_from_tip_mm", {200}}};
    doc["procedure"] = nlohmann::json::parse(R"([
    {"action": "advance", "start_s": 0, "end_s": 1.0, "speed_mm_per_s": 25},
    {"action": "rotate", "start_s": 1.0, "end_s": 1.5, "speed_deg_per_s": 60},
    {"action": "withdraw", "start_s": 1.5, "end_s": 2.0, "speed_mm_per_s": 10}])");
    const model::Scenario scenario = model::read_scenario(doc, "p.json");
    auto run = [&](model::HandCommandSource& hand, std::vector<model::WorldRow>& rows) {
        std::unique_ptr<model::World> world = model::build_world(scenario);
        const auto steps = static_cast<std::size_t>(
            std::ceil(scenario.procedure.end_s() / world->time_step_s() - 1e-9));
        model::SimulationCallbacks callbacks;
        callbacks.on_sample = [&](const model::WorldRow& row, const model::World&) {
            rows.push_back(row);
        };
        return model::run_simulation(*world, scenario, hand, {0, steps, scenario.procedure.end_s()},
                                     callbacks);
    };
    LoggedPlayer player(model::ProcedurePlayer(scenario.procedure, 20.0, scenario.scope.length_mm));
    std::vector<model::WorldRow> played;
    const model::SimulationSummary by_procedure = run(player, played);
    ASSERT_TRUE(by_procedure.complete) << by_procedure.message;
    ASSERT_EQ(player.log.size(), 200u);

    // The recording: the encoder read the commanded depth and roll at every step's end.
    MeasuredRecording recording;
    recording.drive.push_back({0.0, 20.0, 0.0});
    for (std::size_t k = 0; k < player.log.size(); ++k)
        recording.drive.push_back({static_cast<double>(k + 1) * scenario.settings.time_step_s,
                                   player.log[k].insertion_mm, player.log[k].roll_rad});
    recording.end_s = recording.drive.back().time_s;
    recording.duration_s = recording.end_s;
    recording.initial_insertion_mm = 20.0;
    RecordingDrive drive(recording, world_origin_s(recording, scenario.settings.time_step_s));
    std::vector<model::WorldRow> replayed;
    const model::SimulationSummary by_recording = run(drive, replayed);
    ASSERT_TRUE(by_recording.complete) << by_recording.message;

    ASSERT_EQ(replayed.size(), played.size());
    EXPECT_EQ(played.size(), 201u);
    for (std::size_t i = 0; i < played.size(); ++i) {
        EXPECT_EQ(replayed[i].time_s, played[i].time_s) << i;
        EXPECT_EQ(replayed[i].insertion_depth_mm, played[i].insertion_depth_mm) << i;
        EXPECT_EQ(replayed[i].roll_deg, played[i].roll_deg) << i;
        EXPECT_EQ(replayed[i].handle_force_N, played[i].handle_force_N) << i;
        EXPECT_EQ(replayed[i].handle_torque_Nmm, played[i].handle_torque_Nmm) << i;
        EXPECT_EQ(replayed[i].tip_mm, played[i].tip_mm) << i;
        EXPECT_EQ(replayed[i].nodes_mm, played[i].nodes_mm) << i;
        EXPECT_EQ(replayed[i].contact_count, played[i].contact_count) << i;
    }
    EXPECT_NEAR(played.back().insertion_depth_mm, 20.0 + 25.0 - 5.0, 1e-9);
    EXPECT_NEAR(played.back().roll_deg, 30.0, 1e-6);
}

}  // namespace
}  // namespace scopekin::discrepancy
