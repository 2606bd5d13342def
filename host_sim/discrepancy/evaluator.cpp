#include "host_sim/discrepancy/evaluator.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <map>

#include "host_sim/discrepancy/analysis.hpp"

namespace scopekin::discrepancy {

Evaluator::Evaluator(const ModelSpec& model, const MeasuredRecording& data, unsigned threads)
    : model_(model), data_(data), threads_(std::max(1U, threads)) {}

bool window_in_scope(int block, RunScope scope) {
    switch (scope) {
        case RunScope::fit_training: return !is_held_out_block(block);
        case RunScope::fit_held_out: return is_held_out_block(block);
        case RunScope::fit_screening: return is_screening_block(block);
        case RunScope::fit_after_screening: return !is_screening_block(block);
        case RunScope::full:
        case RunScope::fit_all: break;
    }
    return true;
}

ModelPrediction Evaluator::run_baseline(std::vector<RunWindow> windows,
                                        const std::function<void(double)>& progress) {
    ++runs_;
    {
        const std::lock_guard<std::mutex> lock(stored_mutex_);
        stored_.clear();  // the windows' start states change: nothing stored holds any more
        stored_bytes_ = 0;
    }
    windows_ = std::move(windows);
    ModelPrediction p =
        predict(model_, nlohmann::json::array(), data_, progress, &windows_, &states_);
    h_s_ = p.h_s;
    simulated_steps_ += p.steps;
    if (!p.ok) windows_.clear();
    return p;
}

ModelPrediction Evaluator::run_part(const nlohmann::json& effects, RunScope scope,
                                    const std::vector<std::size_t>& which) const {
    ModelPrediction p = scope == RunScope::full || !windowed()
                            ? predict(model_, effects, data_)
                            : predict_windows(model_, effects, data_, windows_, states_, which);
    simulated_steps_ += p.steps;
    return p;
}

ModelPrediction Evaluator::run(const nlohmann::json& effects, RunScope scope) const {
    return run_all(std::vector<std::pair<nlohmann::json, RunScope>>{{effects, scope}}).front();
}

std::vector<ModelPrediction> Evaluator::run_all(const std::vector<nlohmann::json>& lists,
                                                RunScope scope) const {
    std::vector<std::pair<nlohmann::json, RunScope>> requests;
    for (const nlohmann::json& l : lists)
        requests.emplace_back(l, scope);
    return run_all(requests);
}

std::string Evaluator::request_key(const nlohmann::json& effects, RunScope scope) const {
    // Without windows every scope is the full run.
    const int s = windowed() ? static_cast<int>(scope) : static_cast<int>(RunScope::full);
    return std::to_string(s) + effects.dump();
}

bool Evaluator::recall(const std::string& key, ModelPrediction& into) const {
    const std::lock_guard<std::mutex> lock(stored_mutex_);
    for (auto it = stored_.begin(); it != stored_.end(); ++it)
        if (it->key == key) {
            into = it->prediction;
            stored_.splice(stored_.begin(), stored_, it);
            return true;
        }
    return false;
}

void Evaluator::remember(const std::string& key, const ModelPrediction& p) const {
    std::size_t bytes = key.size() + sizeof(ModelPrediction) + p.failure.size();
    for (const auto& o : p.outputs)
        bytes += o.size() * sizeof(Eigen::Vector3d);
    for (const std::string& r : p.step_region)
        bytes += sizeof(std::string) + r.size();
    if (bytes > kRepeatCacheBytes) return;
    const std::lock_guard<std::mutex> lock(stored_mutex_);
    stored_.push_front({key, p, bytes});
    stored_bytes_ += bytes;
    while (stored_bytes_ > kRepeatCacheBytes) {
        stored_bytes_ -= stored_.back().bytes;
        stored_.pop_back();
    }
}

std::vector<ModelPrediction> Evaluator::run_all(
    const std::vector<std::pair<nlohmann::json, RunScope>>& requests) const {
    std::vector<ModelPrediction> out(requests.size());
    std::vector<std::string> keys(requests.size());
    std::vector<std::pair<nlohmann::json, RunScope>> fresh;  // to run
    std::vector<std::size_t> fresh_of;                       // their requests
    std::map<std::string, std::size_t> first_in_batch;
    std::vector<std::pair<std::size_t, std::size_t>> repeated_in_batch;  // (request, first)
    for (std::size_t r = 0; r < requests.size(); ++r) {
        keys[r] = request_key(requests[r].first, requests[r].second);
        if (recall(keys[r], out[r])) {
            ++repeats_;
            continue;
        }
        const auto [at, first] = first_in_batch.emplace(keys[r], r);
        if (!first) {
            repeated_in_batch.emplace_back(r, at->second);
            ++repeats_;
            continue;
        }
        fresh.push_back(requests[r]);
        fresh_of.push_back(r);
    }
    std::vector<ModelPrediction> ran = execute(fresh);
    for (std::size_t k = 0; k < ran.size(); ++k) {
        remember(keys[fresh_of[k]], ran[k]);
        out[fresh_of[k]] = std::move(ran[k]);
    }
    for (const auto& [r, first] : repeated_in_batch)
        out[r] = out[first];
    return out;
}

std::vector<ModelPrediction> Evaluator::execute(
    const std::vector<std::pair<nlohmann::json, RunScope>>& requests) const {
    if (requests.empty()) return {};
    // Tasks: a full run is one task; a windowed run is split by windows into as many parts as
    // leave no thread idle (one part each when there are at least as many runs as threads).
    struct Task {
        std::size_t request;
        std::vector<std::size_t> windows;
    };
    std::vector<Task> tasks;
    const std::size_t parts =
        std::max<std::size_t>(1, threads_ / std::max<std::size_t>(1, requests.size()));
    for (std::size_t r = 0; r < requests.size(); ++r) {
        ++runs_;
        if (requests[r].second == RunScope::full || !windowed()) {
            tasks.push_back({r, {}});
            continue;
        }
        std::vector<std::size_t> which;
        for (std::size_t w = 0; w < windows_.size(); ++w)
            if (window_in_scope(windows_[w].block, requests[r].second)) which.push_back(w);
        const std::size_t n = std::min(parts, which.size());
        for (std::size_t part = 0; part < n; ++part) {
            Task t{r, {}};
            for (std::size_t k = part; k < which.size(); k += n)
                t.windows.push_back(which[k]);
            tasks.push_back(std::move(t));
        }
    }
    std::vector<ModelPrediction> results(tasks.size());
    std::atomic<std::size_t> next{0};
    auto worker = [&] {
        for (std::size_t k = next++; k < tasks.size(); k = next++)
            results[k] = run_part(requests[tasks[k].request].first,
                                  requests[tasks[k].request].second, tasks[k].windows);
    };
    std::vector<std::future<void>> workers;
    for (unsigned w = 0; w < std::min<std::size_t>(threads_, tasks.size()); ++w)
        workers.push_back(std::async(std::launch::async, worker));
    for (auto& w : workers)
        w.get();
    // Parts of one windowed run fill disjoint samples: merge them.
    std::vector<ModelPrediction> out(requests.size());
    std::vector<bool> seen(requests.size(), false);
    for (std::size_t k = 0; k < tasks.size(); ++k) {
        ModelPrediction& into = out[tasks[k].request];
        ModelPrediction& part = results[k];
        if (!seen[tasks[k].request]) {
            into = std::move(part);
            seen[tasks[k].request] = true;
            continue;
        }
        if (!into.ok) continue;
        if (!part.ok) {
            into = std::move(part);
            continue;
        }
        merge_outputs(part, into);
    }
    return out;
}

void merge_outputs(const ModelPrediction& from, ModelPrediction& into) {
    into.steps += from.steps;
    for (std::size_t o = 0; o < into.outputs.size() && o < from.outputs.size(); ++o)
        for (std::size_t i = 0; i < into.outputs[o].size(); ++i)
            if (!std::isnan(from.outputs[o][i].x())) into.outputs[o][i] = from.outputs[o][i];
}

}  // namespace scopekin::discrepancy
