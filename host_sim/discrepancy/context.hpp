#pragma once
// What every stage of the discrepancy workflow (stages.hpp) works from, made once and then
// passed by const reference: the recording with the spans the fits score, the noise estimated
// from it, the model, the evaluator that runs the model under the recording (whole, or on the
// fit windows), and the model as given (the baseline every fit starts from and is judged
// against).
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/analysis.hpp"
#include "host_sim/discrepancy/evaluator.hpp"
#include "host_sim/discrepancy/fit_windows.hpp"
#include "host_sim/discrepancy/measured_recording.hpp"
#include "host_sim/discrepancy/model_spec.hpp"
#include "host_sim/discrepancy/robust_objective.hpp"

namespace scopekin::discrepancy {

struct WorkflowOptions {
    nlohmann::json model;  ///< the current model (default_model() if not given)
    std::string model_source = "default model";
    unsigned threads = 2;
    double significance = 2.0;  ///< held-out RMS error / noise above which an output disagrees
    double min_share = 0.75;    ///< of the excess error a named effect must explain
    /// Recording seconds a fit's run simulates at most (fit_windows.hpp); longer recordings are
    /// fitted on windows.
    double fit_budget_s = kDefaultFitBudget_s;
    /// Only drive the model and compare: verdict none (every output within its noise) or
    /// disagrees; no effect is searched (`--compare-only`).
    bool compare_only = false;
    /// An unexplained recording on full runs whose encoder stops deciding the prediction is
    /// judged again up to there (workflow.hpp); off in that second pass.
    bool judge_predictable_part = true;
    /// Stage text and overall fraction done, now and then.
    std::function<void(const std::string&, double)> progress;
};

struct DiscrepancyContext {
    /// Checks the fit budget, places the fit windows, estimates the noise and reads the model, in
    /// that order (DiscrepancyInputError, model::ModelError saying what is wrong). The model as
    /// given is run by run_model_as_given.
    DiscrepancyContext(const MeasuredRecording& recording, const WorkflowOptions& options);
    DiscrepancyContext(const DiscrepancyContext&) = delete;
    DiscrepancyContext& operator=(const DiscrepancyContext&) = delete;

    /// The model as given over the whole recording (saving the windows' states): `baseline` and
    /// its costs. DiscrepancyInputError if it cannot follow the recording.
    void run_model_as_given(const std::function<void(double)>& progress);

    /// The fits' training cost over the screening blocks only (their rows' capped residuals; the
    /// other blocks' rows, which a fit_screening run leaves unrun, count nothing).
    double screening_cost(const ModelPrediction& p) const;

    /// normalised_residuals (analysis.hpp) of a prediction against this recording and noise; on
    /// the fits' training samples with outlier blocks capped (robust_objective.hpp), the fits'
    /// objective.
    Eigen::VectorXd residuals(const ModelPrediction& p, SampleSet set) const {
        Eigen::VectorXd r = normalised_residuals(data, p, sigma, set);
        return set == SampleSet::fit_training ? cap_outlier_blocks(training_rows, std::move(r)) : r;
    }

    const WorkflowOptions& options;
    MeasuredRecording data;  ///< the recording, with the spans the fits score (fit_spans_s)
    std::vector<RunWindow>
        windows;                ///< the fit windows; none: every run covers the whole recording
    std::vector<double> sigma;  ///< noise SD per output (estimate_noise)
    double noise_floor = 0.0;   ///< held-out cost of noise alone: 1 per assessed output
    /// The training cost of noise alone: 1 per assessed output with training samples.
    double training_noise_floor() const;
    BlockRows training_rows;  ///< the fits' training rows' blocks (robust_objective.hpp)
    ModelSpec model;
    Evaluator evaluator;           ///< runs `model` under `data`
    ModelPrediction baseline;      ///< the model as given, whole recording
    double cost_before = 0.0;      ///< its held-out cost
    double cost_before_fit = 0.0;  ///< on the held-out windows (all held-out data without windows)
};

}  // namespace scopekin::discrepancy
