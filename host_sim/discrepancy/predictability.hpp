#pragma once
// How far a recording's encoder determines the model's prediction. The model is driven by the
// insertion/roll encoder, which resolves 0.01 mm and 0.0001 rad (host_sim/recording/RECORDING.md,
// "Numbers"): the hand's true motion is anywhere within half a count of what was recorded. Where
// a deep insertion holds the scope near its static friction limit, a stick-or-slip branch can
// hang on far less than that (on the robustness sweep's deep procedure E, 0.001 mm of initial
// insertion decided whether the scope slipped in a 12-20 N sawtooth or locked at 50-60 N;
// host_sim/discrepancy/README.md, "The truth's reach"), and then no model, the true one included,
// can predict the recording after the branch from the hand's record.
//
// The test: the model is run twice more, with the whole drive moved by +half and by -half a count
// of both encoders. Where the two predictions part by kDivergenceRatio times an output's noise
// or more (an output the model leaves beyond its noise), over at least half of a kDivergenceWindow_s span, the record no longer decides the
// prediction; the recording is predictable up to the sample before the branch (where they first
// differ by more than kAgreementRatio noise SDs within that span). A stiff but continuous response (a locked scope's handle
// force moves with the insertion, a few N/mm: 0.01 mm is a few noise SDs) stays under the ratio;
// an event one run has a step earlier is a spike of a few samples; a branch (newtons, for
// seconds) is neither.
#include <cstddef>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/context.hpp"
#include "host_sim/discrepancy/measured_recording.hpp"
#include "host_sim/discrepancy/model_run.hpp"

namespace scopekin::discrepancy {

/// One count of the recording's encoders (RECORDING.md: insertion_mm 0.01 mm, roll_rad 0.0001 rad).
inline constexpr double kInsertionCount_mm = 0.01;
inline constexpr double kRollCount_rad = 0.0001;
/// The two predictions part where, on an assessed output, at least half of this span's samples
/// differ by kDivergenceRatio noise SDs or more.
inline constexpr double kDivergenceWindow_s = 1.0;
inline constexpr double kDivergenceRatio = 10.0;
/// Within the parting span, the branch is the first sample at which the runs differ by more than
/// this many noise SDs (the workflow's significance threshold).
inline constexpr double kAgreementRatio = 2.0;

/// The recording with its whole drive (and its initial insertion) moved by the given amounts.
MeasuredRecording with_drive_offset(const MeasuredRecording& data, double insertion_mm,
                                    double roll_rad);

/// The recording up to `end_s` (drive, outputs, region labels; a thinned output keeps every
/// full-rate sample, which only estimates the sensor's noise). DiscrepancyInputError if less than
/// kMinDuration_s would be left.
MeasuredRecording truncated_at(const MeasuredRecording& data, double end_s);

/// The recording time up to which two predictions of the same model under drives within the
/// encoder's resolution agree, on the outputs `counted` (MeasuredRecording::outputs order): the
/// first kDivergenceWindow_s span (starting at a sample) with at least half its samples
/// kDivergenceRatio noise SDs apart on a counted output is the parting; the sample before the
/// first one from there on at which that output's two runs differ by more than kAgreementRatio
/// SDs (the branch) is the answer. None when they never part.
std::optional<double> predictable_until(const MeasuredRecording& data, const ModelPrediction& a,
                                        const ModelPrediction& b, const std::vector<double>& sigma,
                                        const std::vector<bool>& counted);

struct Predictability {
    std::optional<double> until_s;  ///< where the record stops deciding the prediction
    nlohmann::ordered_json report;  ///< report.json "predictability"
};

/// The full runs assess_predictability makes: the drive moved by + and - half an encoder count.
inline constexpr std::size_t kPredictabilityRuns = 2;

/// Runs `effects` under the recording's drive moved by + and - half an encoder count (two full
/// runs in parallel) and compares them (predictable_until) on the outputs that `prediction` (the
/// same effects under the drive as recorded) leaves beyond the options' significance on the
/// held-out blocks: a parting only matters where the misfit is (a procedure's slow slide can
/// shift a handle force sawtooth by 0.3 N, 15 noise SDs, that the model still matches).
Predictability assess_predictability(const DiscrepancyContext& context,
                                     const nlohmann::json& effects,
                                     const ModelPrediction& prediction);

}  // namespace scopekin::discrepancy
