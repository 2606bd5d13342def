#include <future>
#include <utility>

#include "host_sim/discrepancy/ranking.hpp"
#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {
namespace {

/// Fitted on windows: the named effects over the whole recording (alongside the uncertainty's
/// runs). Every before/after figure comes from full runs, and the verdict must hold there too.
/// Returns whether it does; `confirmation` says how.
bool confirm_on_whole_recording(const DiscrepancyContext& context, EffectSetFit& named,
                                nlohmann::ordered_json& confirmation) {
    using Json = nlohmann::ordered_json;
    const Evaluator& evaluator = context.evaluator;
    std::future<ModelPrediction> full = std::async(
        std::launch::async, [&] { return evaluator.run(named.effects, RunScope::full); });
    add_uncertainty(named, context);
    ModelPrediction p = full.get();
    const double windows_cost = named.held_out_cost;
    const bool full_ok = p.ok;
    if (full_ok) {
        named.prediction = std::move(p);
        named.held_out_cost =
            context.residuals(named.prediction, SampleSet::held_out).squaredNorm();
    }
    const double full_share =
        full_ok ? share_explained(context.cost_before, named.held_out_cost, context.noise_floor)
                : 0.0;
    confirmation = {{"held_out_cost_on_windows", windows_cost},
                    {"share_explained_on_windows",
                     share_explained(context.cost_before_fit, windows_cost, context.noise_floor)},
                    {"full_run_ok", full_ok},
                    {"full_run_failure", full_ok ? Json(nullptr) : Json(p.failure)},
                    {"held_out_cost_full", named.held_out_cost},
                    {"share_explained_full", full_share},
                    {"holds", full_share >= context.options.min_share}};
    if (full_share < context.options.min_share) {
        // Not confirmed over the whole recording: not named.
        named.held_out_cost = windows_cost;
        return false;
    }
    return true;
}

}  // namespace

Verdict give_verdict(const DiscrepancyContext& context, std::optional<std::size_t> chosen,
                     std::vector<EffectSetFit>& candidates, StageLog& stages) {
    Verdict v;
    if (!chosen) {
        v.verdict = "unexplained";
        return v;
    }
    // Before the confirmation: every held-out cost compared on the same data (the windows').
    v.equally_consistent = equally_consistent(context, candidates, *chosen);
    EffectSetFit& named = candidates[*chosen];
    const bool windowed = context.evaluator.windowed();
    stages.start(windowed ? "uncertainty, and the named effects over the whole recording"
                          : "uncertainty of the named effects",
                 1.0 - 1.0 / kProgressSteps);
    bool holds = true;
    if (windowed)
        holds = confirm_on_whole_recording(context, named, v.confirmation);
    else
        add_uncertainty(named, context);
    v.verdict = holds ? "named" : "unexplained";
    if (holds) v.named = chosen;
    if (!holds) v.equally_consistent.clear();
    return v;
}

}  // namespace scopekin::discrepancy
