#include "host_sim/discrepancy/context.hpp"

namespace scopekin::discrepancy {
namespace {

const MeasuredRecording& with_budget_checked(const MeasuredRecording& recording,
                                             double fit_budget_s) {
    if (!(fit_budget_s >= kMinFitBudget_s))
        throw DiscrepancyInputError("the fit budget must be at least " +
                                    std::to_string(static_cast<int>(kMinFitBudget_s)) +
                                    " s (ten windows of 3 s spin-up and 5 s scored)");
    return recording;
}

double noise_floor_of(const MeasuredRecording& data, const std::vector<double>& sigma) {
    double floor = 0.0;
    for (std::size_t o = 0; o < data.outputs.size(); ++o)
        floor += assessable(sigma, o) ? 1.0 : 0.0;
    if (floor == 0.0)
        throw DiscrepancyInputError(
            data.source +
            ": no output's noise can be estimated from the data (too few samples, "
            "or a sensor that never reads above 0)");
    return floor;
}

}  // namespace

DiscrepancyContext::DiscrepancyContext(const MeasuredRecording& recording,
                                       const WorkflowOptions& options_given)
    : options(options_given),
      data(with_budget_checked(recording, options_given.fit_budget_s)),
      windows(choose_fit_windows(data, options_given.fit_budget_s)),
      sigma(estimate_noise(data)),
      noise_floor(noise_floor_of(data, sigma)),
      model(read_model_spec(options_given.model.is_null() ? default_model() : options_given.model,
                            options_given.model_source)),
      evaluator(model, data, options_given.threads) {
    // The fits score the windows' spans (fit_windows.hpp); without windows, everything.
    for (const RunWindow& w : windows)
        data.fit_spans_s.emplace_back(w.score_from_s, w.end_s);
    training_rows = block_rows(data, sigma, SampleSet::fit_training);
}

double DiscrepancyContext::training_noise_floor() const {
    double floor = 0.0;
    for (std::size_t o = 0; o < data.outputs.size(); ++o)
        floor += assessable(sigma, o) &&
                         samples_in_set(data, data.outputs[o], SampleSet::fit_training) > 0
                     ? 1.0
                     : 0.0;
    return floor;
}

double DiscrepancyContext::screening_cost(const ModelPrediction& p) const {
    return capped_cost_on_blocks(training_rows,
                                 normalised_residuals(data, p, sigma, SampleSet::fit_training),
                                 is_screening_block);
}

void DiscrepancyContext::run_model_as_given(const std::function<void(double)>& progress) {
    baseline = evaluator.run_baseline(windows, progress);
    if (!baseline.ok)
        throw DiscrepancyInputError(
            data.source + ": the model as given cannot follow this recording's hand motion (" +
            baseline.failure + ")");
    cost_before = residuals(baseline, SampleSet::held_out).squaredNorm();
    // The candidates are compared on the held-out windows (all held-out data without windows).
    cost_before_fit = residuals(baseline, SampleSet::fit_held_out).squaredNorm();
}

}  // namespace scopekin::discrepancy
