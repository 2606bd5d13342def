#pragma once
// Runs the model under the recording for the fits: with a list of effects, over the whole
// recording or over its fit windows (fit_windows.hpp), a batch on several threads, counting the
// runs and the recording seconds simulated (report.json "model_runs", "stages").
#include <atomic>
#include <functional>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/fit_windows.hpp"
#include "host_sim/discrepancy/measured_recording.hpp"
#include "host_sim/discrepancy/model_run.hpp"
#include "host_sim/discrepancy/model_spec.hpp"

namespace scopekin::discrepancy {

/// What a run covers: the whole recording, or (with fit windows) the training windows, the
/// held-out ones, all windows, the screening's (is_screening_block) or all but those. Without
/// windows every run is a full run.
enum class RunScope {
    full,
    fit_training,
    fit_held_out,
    fit_all,
    fit_screening,
    fit_after_screening
};

/// Whether a window of `block` is run in `scope` (a windowed scope).
bool window_in_scope(int block, RunScope scope);

/// Copies `from`'s outputs where it has them (not NaN) into `into`: the parts of a windowed run.
void merge_outputs(const ModelPrediction& from, ModelPrediction& into);

/// Runs the model with a list of effects (truth_effects entries); counts the runs; runs a batch
/// on up to `threads` threads (a windowed run alone is split over them by windows). Keeps
/// references to `model` and `data`.
class Evaluator {
public:
    Evaluator(const ModelSpec& model, const MeasuredRecording& data, unsigned threads);
    /// The model as given over the whole recording, saving the states the windows restart from
    /// (`windows` may be empty: no windows, every later run is full).
    ModelPrediction run_baseline(std::vector<RunWindow> windows,
                                 const std::function<void(double)>& progress = {});
    ModelPrediction run(const nlohmann::json& effects, RunScope scope = RunScope::fit_all) const;
    std::vector<ModelPrediction> run_all(const std::vector<nlohmann::json>& effect_lists,
                                         RunScope scope = RunScope::fit_all) const;
    std::vector<ModelPrediction> run_all(
        const std::vector<std::pair<nlohmann::json, RunScope>>& requests) const;
    std::size_t runs() const { return runs_.load(); }
    /// Recording seconds simulated by all runs so far.
    double simulated_s() const { return static_cast<double>(simulated_steps_.load()) * h_s_; }
    bool windowed() const { return !windows_.empty(); }
    const std::vector<RunWindow>& windows() const { return windows_; }

private:
    ModelPrediction run_part(const nlohmann::json& effects, RunScope scope,
                             const std::vector<std::size_t>& which) const;

    const ModelSpec& model_;
    const MeasuredRecording& data_;
    unsigned threads_;
    std::vector<RunWindow> windows_;
    std::vector<model::World::State> states_;
    double h_s_ = 0.01;
    mutable std::atomic<std::size_t> runs_{0};
    mutable std::atomic<std::size_t> simulated_steps_{0};
};

}  // namespace scopekin::discrepancy
