#pragma once
// Runs the model under the recording for the fits: with a list of effects, over the whole
// recording or over its fit windows (fit_windows.hpp), a batch on several threads, counting the
// runs and the recording seconds simulated (report.json "model_runs", "stages").
#include <atomic>
#include <cstddef>
#include <functional>
#include <list>
#include <mutex>
#include <string>
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
///
/// A run is a pure function of its effect list and scope (the model, the recording and the
/// windows' start states are fixed once run_baseline has run), so a request made before (a
/// Gauss-Newton step that lands on a grid point, a refit that retakes a difference) or twice in
/// one batch is answered with the stored prediction, bit for bit, and not run or counted again.
/// The stored predictions are the most recent ones up to kRepeatCacheBytes.
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
    /// Model runs made (repeats answered from the stored predictions are not runs).
    std::size_t runs() const { return runs_.load(); }
    /// Requests answered with a stored prediction.
    std::size_t repeats() const { return repeats_.load(); }
    static constexpr std::size_t kRepeatCacheBytes = std::size_t{512} << 20;
    /// Recording seconds simulated by all runs so far.
    double simulated_s() const { return static_cast<double>(simulated_steps_.load()) * h_s_; }
    bool windowed() const { return !windows_.empty(); }
    const std::vector<RunWindow>& windows() const { return windows_; }

private:
    struct Stored {
        std::string key;
        ModelPrediction prediction;
        std::size_t bytes = 0;
    };
    std::string request_key(const nlohmann::json& effects, RunScope scope) const;
    std::vector<ModelPrediction> execute(
        const std::vector<std::pair<nlohmann::json, RunScope>>& requests) const;
    bool recall(const std::string& key, ModelPrediction& into) const;
    void remember(const std::string& key, const ModelPrediction& p) const;
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
    mutable std::atomic<std::size_t> repeats_{0};
    mutable std::mutex stored_mutex_;
    mutable std::list<Stored> stored_;  ///< most recent first
    mutable std::size_t stored_bytes_ = 0;
};

}  // namespace scopekin::discrepancy
