#include <algorithm>
#include <cmath>

#include "host_sim/discrepancy/ranking.hpp"
#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {
namespace {

/// The runner-up is refined when its screening explained at least this share of the excess: its
/// coarse start may sit far from its own best (a one-parameter grid at 0.7 and 1.0 for a truth at
/// 0.8), so its screening is no measure of what it explains refined.
constexpr double kRefineRunnerUp = 0.25;

/// Points of each round of the line search inside its bracket, and its rounds.
constexpr int kLinePoints = 7;
constexpr int kLineRounds = 2;

/// The neighbours of `x` on a one-parameter candidate's screening axis (its grid, its neutral
/// value and its bounds): the bracket the line search looks inside.
std::pair<double, double> bracket_of(const FittedParameter& p, double x) {
    std::vector<double> axis = p.screen;
    axis.insert(axis.end(), {p.neutral, p.lo, p.hi});
    double a = p.lo, b = p.hi;
    for (double v : axis) {
        if (v < x) a = std::max(a, v);
        if (v > x) b = std::min(b, v);
    }
    return {a, b};
}

/// One-parameter candidates after Levenberg-Marquardt: a derivative-free search between the fit's
/// neighbours on the screening axis (kLineRounds rounds of kLinePoints training runs, each round
/// around the best of the one before). Why: where a stick-and-release event shifts with the
/// parameter the training cost steps (a hidden EI factor 1.15 on procedure C: 252 at 1.12, 13,907
/// at 1.25), and a finite-difference step of 0.1 straddles the step, so the Levenberg-Marquardt
/// iteration stops short (1.122, cost 245); the points between find the dip (noise alone ~6).
/// Keeps the fit when nothing beats it.
void refine_on_axis(const DiscrepancyContext& context, EffectSetFit& fit) {
    if (context.evaluator.windowed()) return;  // long runs: the 10-minute recording's budget
    if (!fit.ok || fit.candidates.size() != 1) return;
    const Candidate& c = candidate_library()[fit.candidates[0]];
    if (c.parameters.size() != 1 || c.parameters[0].screen.empty()) return;
    const FittedParameter& p = c.parameters[0];
    double best = fit.values[0], best_cost = fit.training_cost;
    auto [a, b] = bracket_of(p, best);
    for (int round = 0; round < kLineRounds; ++round) {
        std::vector<double> xs;
        std::vector<nlohmann::json> lists;
        for (int k = 1; k <= kLinePoints; ++k) {
            xs.push_back(a + (b - a) * k / (kLinePoints + 1));
            lists.push_back(nlohmann::json::array({c.entry({xs.back()}, fit.held[0])}));
        }
        const std::vector<ModelPrediction> runs =
            context.evaluator.run_all(lists, RunScope::fit_training);
        for (std::size_t k = 0; k < runs.size(); ++k) {
            if (!runs[k].ok) continue;
            const double cost = context.residuals(runs[k], SampleSet::fit_training).squaredNorm();
            if (cost < best_cost) {
                best = xs[k];
                best_cost = cost;
            }
        }
        const double spacing = (b - a) / (kLinePoints + 1);
        a = std::max(a, best - spacing);
        b = std::min(b, best + spacing);
    }
    if (!(best_cost < fit.training_cost)) return;
    const std::vector<double> start{best};
    EffectSetFit there = fit_effect_set(fit.candidates, context, &start, &fit.held, 0);
    if (there.ok && there.training_cost < fit.training_cost) {
        there.iterations = fit.iterations;
        fit = std::move(there);
    }
}

/// A refined candidate that contains another refined one (ei_profile contains ei_scale) but
/// explains its training data less well has stopped in a poorer basin than the nested one's: fit
/// it again from the nested one's values (ei_scale f as ei_profile (f, f)) and keep the better.
void restart_from_nested(const DiscrepancyContext& context, std::vector<EffectSetFit>& refined,
                         StageLog& stages) {
    for (EffectSetFit& outer : refined) {
        if (!outer.ok || outer.candidates.size() != 1) continue;
        for (const EffectSetFit& inner : refined) {
            if (!inner.ok || inner.candidates.size() != 1 ||
                !(inner.training_cost < outer.training_cost))
                continue;
            const std::vector<double> start =
                nested_start(outer.candidates[0], inner.candidates[0], inner.values);
            if (start.empty()) continue;
            stages.start("fitting " + candidate_library()[outer.candidates[0]].name +
                             " again from " + candidate_library()[inner.candidates[0]].name,
                         (2.0 + static_cast<double>(kRefined)) / kProgressSteps);
            EffectSetFit again = fit_effect_set(outer.candidates, context, &start, &outer.held);
            if (again.ok && again.training_cost < outer.training_cost) outer = std::move(again);
        }
    }
}

}  // namespace

std::vector<EffectSetFit> refine_candidates(const DiscrepancyContext& context,
                                            const std::vector<EffectSetFit>& screened,
                                            StageLog& stages) {
    std::vector<EffectSetFit> candidates = screened;
    std::sort(candidates.begin(), candidates.end(), by_held_out);
    // The best single effect, and the runner-up when its screening explained kRefineRunnerUp of
    // the excess and the best refined leaves more than 1 %, or the best refined explains too little: two effects that explain nearly the same
    // (ei_profile with equal factors is ei_scale; on a short insertion, where the handle end never
    // bends, any ei_profile) are both refined before they are compared. Never one whose screening
    // explained nothing.
    double best_refined_share = 0.0;
    std::size_t tried = 0;  // candidates[0, tried) were refined (or tried)
    for (std::size_t k = 0; k < std::min(kRefined, candidates.size()); ++k) {
        if (!candidates[k].ok) continue;
        const double screened_share = share_of(context, candidates[k]);
        if (k > 0 && !(screened_share > 0.0)) break;
        // Fitted on windows (long runs): the runner-up only when the best explains too little.
        if (k > 0 && best_refined_share >= context.options.min_share &&
            (context.evaluator.windowed() || screened_share < kRefineRunnerUp))
            break;
        const std::size_t c = candidates[k].candidates[0];
        stages.start("fitting " + candidate_library()[c].name,
                     (2.0 + static_cast<double>(k)) / kProgressSteps);
        const std::vector<double> start = candidates[k].values;
        const std::vector<nlohmann::json> held = candidates[k].held;
        EffectSetFit refined = fit_effect_set({c}, context, &start, &held);
        refine_on_axis(context, refined);
        if (refined.ok) candidates[k] = std::move(refined);
        best_refined_share = std::max(best_refined_share, share_of(context, candidates[k]));
        tried = k + 1;
    }
    std::vector<EffectSetFit> first(candidates.begin(),
                                    candidates.begin() + static_cast<std::ptrdiff_t>(tried));
    restart_from_nested(context, first, stages);
    std::move(first.begin(), first.end(), candidates.begin());
    std::sort(candidates.begin(), candidates.end(), by_held_out);
    // Ranked by held-out error, and by the information criterion among those within kTieShare of
    // the best.
    prefer_simpler(context, candidates);
    return candidates;
}

}  // namespace scopekin::discrepancy
