#pragma once
// Comparing a model run with the measurements: the sensor noise estimated from the data, the
// blocked split into training and held-out time, errors per output, and where the disagreement
// is (by region, phase, speed and insertion depth).
//
// Noise. Each component's noise SD is estimated from the measured signal alone, as the robust
// SD of its second differences divided by sqrt(6) (for white noise e_i, e_{i+1} - 2 e_i + e_{i-1}
// has variance 6 sigma^2; a smooth motion sampled at 30 Hz adds little, and the median keeps
// stick-slip jumps out). An output's noise is the root sum of squares over its components. A
// thinned output (the handle's 1 kHz, compared every 33 ms) is estimated from every sample
// delivered (MeasuredSeries::full_rate): the sensor's noise is white per sample, and the signal's
// curvature over 1 ms is a thousandth of that over 33 ms (since 2026-12-01; before, the handle
// force's noise read 1.7 to 13 times the sensor's 0.02 N on the robustness sweep's procedures).
// A sensor whose noise is correlated from sample to sample (filtered) would read low.
//
// Hold-out. Residuals are autocorrelated, so samples are not held out one by one: the drive's
// span is cut into kBlocks equal blocks and blocks 1, 4, 7 (of 0..9) are held out.
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/measured_recording.hpp"
#include "host_sim/discrepancy/model_run.hpp"

namespace scopekin::discrepancy {

inline constexpr int kBlocks = 10;
/// The block (0 .. kBlocks - 1) a recording time falls in.
int block_of(const MeasuredRecording& data, double time_s);
bool is_held_out_block(int block);
/// The training blocks the screening's grid is costed on when fitted on windows (0, 3, 6, 9: four
/// of the seven, spread over the recording): the grid only picks a start, and on a long recording
/// it is most of the screening's runs (host_sim/discrepancy/README.md, the 10-minute bench).
bool is_screening_block(int block);

/// fit_training and fit_held_out: the training / held-out samples within the fits' scored spans
/// (MeasuredRecording::fit_spans_s; all of them when it is empty).
enum class SampleSet {
    training,
    held_out,
    all,
    fit_training,
    fit_held_out
};
bool in_set(const MeasuredRecording& data, double time_s, SampleSet set);
/// How many of an output's samples fall in a set.
std::size_t samples_in_set(const MeasuredRecording& data, const MeasuredSeries& series,
                           SampleSet set);

/// Second differences needed per component for a noise estimate.
inline constexpr std::size_t kMinNoiseSamples = 20;
/// Noise SD per output (MeasuredRecording::outputs order), combined over components [output unit]; 0
/// where it cannot be estimated (a tip force sensor that reads 0 nearly all the time): such an
/// output is not assessed (not in the costs, never significant), only reported.
std::vector<double> estimate_noise(const MeasuredRecording& data);
bool assessable(const std::vector<double>& sigma, std::size_t output);

/// RMS of |measured - predicted| over a sample set [output unit]; 0 for an empty set.
double rms_error(const MeasuredRecording& data, const ModelPrediction& p, std::size_t output,
                 SampleSet set);

/// The fitting residual: for every output o and sample i of the set, the components of
/// (measured - predicted) / (sigma_o sqrt(n_o)). Its squared norm is the sum over outputs of
/// the mean squared error in units of the noise: about 1 per output for a perfect model.
Eigen::VectorXd normalised_residuals(const MeasuredRecording& data, const ModelPrediction& p,
                                     const std::vector<double>& sigma, SampleSet set);

/// What the hand does at t: "push", "pull", "hold" or "twist" (from the encoder's rates over 0.2 s).
std::string phase_at(const MeasuredRecording& data, double time_s);

/// Where the disagreement is: for each grouping (region, phase, speed, depth), each group's
/// sample count and, per output, RMS error and its ratio to the noise, with `significant` set
/// where the ratio exceeds `threshold` on at least 10 samples.
nlohmann::ordered_json locate(const MeasuredRecording& data, const ModelPrediction& p,
                              const std::vector<double>& sigma, double threshold);

}  // namespace scopekin::discrepancy
