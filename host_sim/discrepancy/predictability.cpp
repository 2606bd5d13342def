#include "host_sim/discrepancy/predictability.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <sstream>
#include <string>
#include <utility>

namespace scopekin::discrepancy {

MeasuredRecording with_drive_offset(const MeasuredRecording& data, double insertion_mm,
                                    double roll_rad) {
    MeasuredRecording moved = data;
    for (DriveSample& s : moved.drive) {
        s.insertion_mm += insertion_mm;
        s.roll_rad += roll_rad;
    }
    moved.initial_insertion_mm += insertion_mm;
    return moved;
}

MeasuredRecording truncated_at(const MeasuredRecording& data, double end_s) {
    if (!(end_s - data.start_s >= kMinDuration_s)) {
        std::ostringstream message;
        message.precision(3);
        message << data.source << ": only " << end_s - data.start_s
                << " s would be left of the recording; the workflow needs at least "
                << kMinDuration_s << " s";
        throw DiscrepancyInputError(message.str());
    }
    MeasuredRecording cut = data;
    cut.drive.resize(static_cast<std::size_t>(
        std::upper_bound(data.drive.begin(), data.drive.end(), end_s,
                         [](double t, const DriveSample& s) { return t < s.time_s; }) -
        data.drive.begin()));
    cut.end_s = cut.drive.back().time_s;
    cut.duration_s = cut.end_s - cut.start_s;
    // Every series is in time order: keep each one's samples up to the drive's last sample.
    const auto kept = [last = cut.end_s](const std::vector<double>& t) {
        return static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), last) - t.begin());
    };
    cut.outputs.clear();
    for (const MeasuredSeries& m : data.outputs) {
        const std::size_t n = kept(m.time_s);
        if (n < 20) continue;  // as extraction: an output needs 20 samples
        MeasuredSeries& part = cut.outputs.emplace_back(m);
        part.time_s.resize(n);
        part.value.resize(n);
    }
    const std::size_t labels = kept(data.region_time_s);
    cut.region_time_s.resize(labels);
    cut.region.resize(labels);
    cut.fit_spans_s.clear();  // the windows are placed again on what is left
    return cut;
}

namespace {

/// |a - b| / sigma at sample i of output o (the largest component).
double parted_by(const MeasuredRecording& data, const ModelPrediction& a, const ModelPrediction& b,
                 const std::vector<double>& sigma, std::size_t o, std::size_t i) {
    double d = 0.0;
    for (int c = 0; c < data.outputs[o].components; ++c)
        d = std::max(d, std::abs(a.outputs[o][i][c] - b.outputs[o][i][c]));
    return d / sigma[o];
}

/// The first of output o's samples from which, over kDivergenceWindow_s, at least half the
/// samples differ by kDivergenceRatio noise SDs or more (infinity: never). Half the span, not its
/// RMS: an event that one run has a step earlier is a spike of a few samples, after which the two
/// agree again; a branch stays apart.
double first_parting(const MeasuredRecording& data, const ModelPrediction& a,
                     const ModelPrediction& b, const std::vector<double>& sigma, std::size_t o) {
    const std::vector<double>& t = data.outputs[o].time_s;
    std::size_t apart = 0;  // samples of [t[i], t[i] + window) that differ by the ratio
    std::size_t end = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
        while (end < t.size() && t[end] < t[i] + kDivergenceWindow_s) {
            apart += parted_by(data, a, b, sigma, o, end) >= kDivergenceRatio ? 1U : 0U;
            ++end;
        }
        const bool full_span = t[end - 1] - t[i] >= 0.5 * kDivergenceWindow_s;
        if (full_span && 2 * apart >= end - i) return t[i];
        apart -= parted_by(data, a, b, sigma, o, i) >= kDivergenceRatio ? 1U : 0U;
    }
    return INFINITY;
}

}  // namespace

std::optional<double> predictable_until(const MeasuredRecording& data, const ModelPrediction& a,
                                        const ModelPrediction& b, const std::vector<double>& sigma,
                                        const std::vector<bool>& counted) {
    double parting = INFINITY;
    std::size_t first = 0;  // the output that parts first
    for (std::size_t o = 0; o < data.outputs.size(); ++o) {
        if (!assessable(sigma, o) || !counted.at(o)) continue;
        const double t = first_parting(data, a, b, sigma, o);
        if (t < parting) {
            parting = t;
            first = o;
        }
    }
    if (!std::isfinite(parting)) return std::nullopt;
    // From the parting's first sample on, the first at which that output's runs differ by more
    // than kAgreementRatio noise SDs is the branch; what came before it the record decides.
    const std::vector<double>& t = data.outputs[first].time_s;
    std::size_t i = 0;
    while (t[i] < parting)
        ++i;
    while (i < t.size() && parted_by(data, a, b, sigma, first, i) <= kAgreementRatio)
        ++i;
    return i == 0 ? data.start_s : t[i - 1];
}

Predictability assess_predictability(const DiscrepancyContext& context,
                                     const nlohmann::json& effects,
                                     const ModelPrediction& prediction) {
    // The outputs the model leaves beyond its noise: where a parting would matter.
    std::vector<bool> counted(context.data.outputs.size(), false);
    nlohmann::ordered_json misfit = nlohmann::ordered_json::array();
    for (std::size_t o = 0; o < counted.size(); ++o) {
        if (!assessable(context.sigma, o) || !prediction.ok) continue;
        const double ratio =
            rms_error(context.data, prediction, o, SampleSet::held_out) / context.sigma[o];
        counted[o] = ratio > context.options.significance;
        if (counted[o]) misfit.push_back(output_name(context.data.outputs[o].id));
    }
    const MeasuredRecording plus =
        with_drive_offset(context.data, 0.5 * kInsertionCount_mm, 0.5 * kRollCount_rad);
    const MeasuredRecording minus =
        with_drive_offset(context.data, -0.5 * kInsertionCount_mm, -0.5 * kRollCount_rad);
    std::future<ModelPrediction> run_plus =
        std::async(std::launch::async, [&] { return predict(context.model, effects, plus); });
    const ModelPrediction b = predict(context.model, effects, minus);
    const ModelPrediction a = run_plus.get();
    Predictability result;
    result.report = {
        {"effects", effects},
        {"drive_offsets",
         {{"insertion_mm", 0.5 * kInsertionCount_mm}, {"roll_rad", 0.5 * kRollCount_rad}}},
        {"rule",
         "the model run with the whole drive moved by + and - half an encoder count; the record "
         "decides the prediction until the two part on an output the model leaves beyond its "
         "noise (held out): half of a 1 s span " +
             std::to_string(static_cast<int>(kDivergenceRatio)) +
             " noise SDs or more apart; the part judged ends at the sample before the first "
             "beyond " +
             std::to_string(static_cast<int>(kAgreementRatio)) + " SDs there"},
        {"outputs_compared", misfit},
        {"runs_ok", a.ok && b.ok}};
    if (!a.ok || !b.ok) {
        result.report["until_s"] = nullptr;
        result.report["why"] = "a moved run failed: " + (a.ok ? b.failure : a.failure);
        return result;
    }
    result.until_s = predictable_until(context.data, a, b, context.sigma, counted);
    result.report["until_s"] = result.until_s ? nlohmann::json(*result.until_s) : nullptr;
    // How far apart the two runs end up: the largest difference per assessed output.
    nlohmann::ordered_json parted = nlohmann::ordered_json::object();
    for (std::size_t o = 0; o < context.data.outputs.size(); ++o) {
        if (!assessable(context.sigma, o)) continue;
        double largest = 0.0;
        for (std::size_t i = 0; i < context.data.outputs[o].time_s.size(); ++i)
            largest = std::max(largest, parted_by(context.data, a, b, context.sigma, o, i));
        parted[output_name(context.data.outputs[o].id)] = largest * context.sigma[o];
    }
    result.report["largest_difference"] = parted;
    return result;
}

}  // namespace scopekin::discrepancy
