#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "host_sim/discrepancy/ranking.hpp"
#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {
namespace {

/// The runner-up is refined when its screening explained at least this share of the excess: its
/// coarse start may sit far from its own best (a one-parameter grid at 0.7 and 1.0 for a truth at
/// 0.8), so its screening is no measure of what it explains refined.
constexpr double kRefineRunnerUp = 0.25;

/// Fitted on windows (a long recording), the runner-up is refined only when its screening
/// explained at least this share: there the screen is a grid over each effect's plausible range,
/// not a coarse start, and a runner-up it found explaining next to nothing will not explain 75 %
/// refined. Seen on the 10-minute bench's pair (ei_scale 0.88 + viscous 0.003): viscous friction
/// refined explained 74 %, and `sigmoid_mobility`, screened at 0.04 %, took 9 runs and 11 s to
/// stay there.
constexpr double kWindowedRunnerUpFloor = 0.1;

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

/// The line search's tries beyond the fit's own bracket: the screening profile's other dips.
constexpr std::size_t kOtherDips = 2;

/// Training runs of `fit`'s effect set at each of `points` (its parameters' values, in order): the
/// index of the lowest training cost and that cost (points.size() and infinity when every run
/// failed).
std::pair<std::size_t, double> lowest_training_cost(
    const DiscrepancyContext& context, const EffectSetFit& fit,
    const std::vector<std::vector<double>>& points) {
    std::vector<nlohmann::json> lists;
    for (const std::vector<double>& x : points)
        lists.push_back(entries_of(fit, x));
    const std::vector<ModelPrediction> runs =
        context.evaluator.run_all(lists, RunScope::fit_training);
    std::pair<std::size_t, double> lowest{points.size(), std::numeric_limits<double>::infinity()};
    for (std::size_t k = 0; k < runs.size(); ++k) {
        if (!runs[k].ok) continue;
        const double cost = context.residuals(runs[k], SampleSet::fit_training).squaredNorm();
        if (cost < lowest.second) lowest = {k, cost};
    }
    return lowest;
}

/// kLineRounds rounds of kLinePoints training runs inside (a, b), each round around the best so
/// far (`from`, at `from_cost`, counts: the fit in its own bracket; NaN in another); lowers `best`
/// / `best_cost` where a point beats them.
void line_search(const DiscrepancyContext& context, const EffectSetFit& fit, double a, double b,
                 double from, double from_cost, double& best, double& best_cost) {
    double centre = from, centre_cost = from_cost;
    for (int round = 0; round < kLineRounds; ++round) {
        std::vector<std::vector<double>> xs;
        for (int k = 1; k <= kLinePoints; ++k)
            xs.push_back({a + (b - a) * k / (kLinePoints + 1)});
        const auto [lowest, round_cost] = lowest_training_cost(context, fit, xs);
        const double round_best =
            lowest < xs.size() ? xs[lowest][0] : std::numeric_limits<double>::quiet_NaN();
        if (std::isnan(round_best) && std::isnan(centre)) return;
        if (round_cost < centre_cost || std::isnan(centre)) {
            centre = round_best;
            centre_cost = round_cost;
        }
        const double spacing = (b - a) / (kLinePoints + 1);
        a = std::max(a, centre - spacing);
        b = std::min(b, centre + spacing);
    }
    if (centre_cost < best_cost) {
        best = centre;
        best_cost = centre_cost;
    }
}

/// One-parameter candidates after Levenberg-Marquardt: a derivative-free search between the fit's
/// neighbours on the screening axis, and between the neighbours of the screening profile's other
/// dips (kOtherDips at most). Why: where a stick-and-release event shifts with the parameter the
/// training cost steps (a hidden EI factor 1.15 on procedure C: 252 at 1.12, 13,907 at 1.25), and
/// a finite-difference step of 0.1 straddles the step, so the Levenberg-Marquardt iteration stops
/// short (1.122, cost 245); the points between find the dip (noise alone ~6). And the profile can
/// have two dips with the truth in the poorer one's bracket (a hidden EI factor 1.3 on C: 650 at
/// 1.12, 15,483 at 1.25, 965 at 1.4). Keeps the fit when nothing beats it.
void refine_on_axis(const DiscrepancyContext& context, EffectSetFit& fit,
                    const std::vector<std::pair<double, double>>& profile) {
    if (context.evaluator.windowed()) return;  // long runs: the 10-minute recording's budget
    if (!fit.ok || fit.candidates.size() != 1) return;
    const Candidate& c = candidate_library()[fit.candidates[0]];
    if (c.parameters.size() != 1 || c.parameters[0].screen.empty()) return;
    const FittedParameter& p = c.parameters[0];
    double best = fit.values[0], best_cost = fit.training_cost;
    const auto own = bracket_of(p, best);
    line_search(context, fit, own.first, own.second, best, best_cost, best, best_cost);
    std::size_t others = 0;
    for (double dip : profile_dips(profile)) {
        if (others == kOtherDips) break;
        if (dip >= own.first && dip <= own.second) continue;  // the fit's own basin
        const auto [a, b] = bracket_of(p, dip);
        line_search(context, fit, a, b, std::numeric_limits<double>::quiet_NaN(),
                    std::numeric_limits<double>::infinity(), best, best_cost);
        ++others;
    }
    if (!(best_cost < fit.training_cost)) return;
    const std::vector<double> start{best};
    EffectSetFit there = fit_effect_set(fit.candidates, context, &start, &fit.held, 0);
    if (there.ok && there.training_cost < fit.training_cost) {
        there.iterations = fit.iterations;
        fit = std::move(there);
    }
}

/// Points per axis of each round of the two-parameter box search, and its rounds.
constexpr int kBoxPoints = 5;
constexpr int kBoxRounds = 2;

/// The second neighbours of `x` on a parameter's screening axis (its grid, neutral value and
/// bounds): two grid cells either way, the box a valley between the axes can cross.
std::pair<double, double> wide_bracket_of(const FittedParameter& p, double x) {
    const auto [a, b] = bracket_of(p, x);
    return {a > p.lo ? bracket_of(p, a).first : a, b < p.hi ? bracket_of(p, b).second : b};
}

}  // namespace

std::vector<FittedParameter> two_screened_parameters(const EffectSetFit& fit) {
    if (!fit.ok) return {};
    std::vector<FittedParameter> params = parameters_of(fit);
    if (params.size() != 2 || params[0].screen.empty() || params[1].screen.empty()) return {};
    return params;
}

bool leaves_training_excess(double training_cost, double training_noise_floor) {
    return !(training_cost - training_noise_floor < kMinRestCost);  // a NaN cost leaves excess
}

/// Why a box: a hidden distal softening (ei_profile tip 0.6, handle 1.0) on a 320 mm insertion
/// (procedure B) leaves a long, stepped valley (the data see the tip's factor and barely the
/// slope): the fit from the screening's best point (0.5, 2.0) stopped poorer than ei_scale, and
/// from ei_scale's (0.647, 0.647) it did not move.
void refine_in_box(const DiscrepancyContext& context, EffectSetFit& fit, StageLog& stages) {
    if (context.evaluator.windowed()) return;  // long runs: the 10-minute recording's budget
    const std::vector<FittedParameter> params = two_screened_parameters(fit);
    if (params.empty() ||
        !leaves_training_excess(fit.training_cost, context.training_noise_floor()))
        return;
    stages.start("searching " + set_name(fit) + "'s box",
                 (2.0 + static_cast<double>(kRefined)) / kProgressSteps);
    std::vector<double> best = fit.values;
    double best_cost = fit.training_cost;
    std::array<std::pair<double, double>, 2> box = {wide_bracket_of(params[0], best[0]),
                                                    wide_bracket_of(params[1], best[1])};
    for (int round = 0; round < kBoxRounds; ++round) {
        std::vector<std::vector<double>> xs;
        std::array<double, 2> spacing{};
        for (std::size_t j = 0; j < 2; ++j)
            spacing[j] = (box[j].second - box[j].first) / (kBoxPoints + 1);
        for (int u = 1; u <= kBoxPoints; ++u)
            for (int v = 1; v <= kBoxPoints; ++v)
                xs.push_back({box[0].first + spacing[0] * u, box[1].first + spacing[1] * v});
        const auto [lowest, cost] = lowest_training_cost(context, fit, xs);
        if (lowest < xs.size() && cost < best_cost) {
            best = xs[lowest];
            best_cost = cost;
        }
        for (std::size_t j = 0; j < 2; ++j)
            box[j] = {std::max(params[j].lo, best[j] - spacing[j]),
                      std::min(params[j].hi, best[j] + spacing[j])};
    }
    if (!(best_cost < fit.training_cost)) return;
    EffectSetFit there = fit_effect_set(fit.candidates, context, &best, &fit.held);
    if (there.ok && there.training_cost < fit.training_cost) {
        there.iterations = fit.iterations;
        fit = std::move(there);
    }
}

namespace {

/// Starts for `target` from a nested `source` that fits better: the richer from the simpler's
/// values (nested_start: ei_scale f as ei_profile (f, f)), or the simpler near the richer's
/// (nested_projections: ei_profile (tip, handle) as ei_scale at the tip and at the mean).
std::vector<std::vector<double>> nested_starts(const EffectSetFit& target,
                                               const EffectSetFit& source) {
    const std::size_t t = target.candidates[0], s = source.candidates[0];
    std::vector<double> richer = nested_start(t, s, source.values);
    if (!richer.empty()) return {richer};
    return nested_projections(s, t, source.values);
}

/// Of two nested refined candidates (ei_profile contains ei_scale) the one that explains its
/// training data less well has stopped in a poorer basin: fit it again from the other's values
/// (nested_starts) and keep the better. Both ways: a richer one that fits worse than the simpler
/// it contains can at least match it from there; a simpler one that fits worse may have missed a
/// narrow dip the richer one's extra freedom found (a hidden EI factor 1.3 on procedure C, whose
/// training cost steps with a stick-and-release between 1.25 and 1.4: the line search stopped at
/// ei_scale 1.273, cost 31.3, and ei_profile found (1.28, 1.292), 19.1; ei_profile then earned its
/// parameters against that ei_scale on the held-out data and was named).
void restart_nested(const DiscrepancyContext& context, std::vector<EffectSetFit>& refined,
                    StageLog& stages) {
    for (EffectSetFit& target : refined) {
        if (!target.ok || target.candidates.size() != 1) continue;
        for (const EffectSetFit& source : refined) {
            if (!source.ok || source.candidates.size() != 1 ||
                !(source.training_cost < target.training_cost))
                continue;
            const std::vector<std::vector<double>> starts = nested_starts(target, source);
            if (starts.empty()) continue;
            stages.start("fitting " + candidate_library()[target.candidates[0]].name +
                             " again from " + candidate_library()[source.candidates[0]].name,
                         (2.0 + static_cast<double>(kRefined)) / kProgressSteps);
            for (const std::vector<double>& start : starts) {
                EffectSetFit again =
                    fit_effect_set(target.candidates, context, &start, &target.held);
                if (again.ok && again.training_cost < target.training_cost)
                    target = std::move(again);
            }
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
        // Fitted on windows (long runs): the runner-up only when the best explains too little,
        // and only one whose screening explained kWindowedRunnerUpFloor.
        if (k > 0 && context.evaluator.windowed() && screened_share < kWindowedRunnerUpFloor) break;
        if (k > 0 && best_refined_share >= context.options.min_share &&
            (context.evaluator.windowed() || screened_share < kRefineRunnerUp))
            break;
        const std::size_t c = candidates[k].candidates[0];
        stages.start("fitting " + candidate_library()[c].name,
                     (2.0 + static_cast<double>(k)) / kProgressSteps);
        const std::vector<double> start = candidates[k].values;
        const std::vector<nlohmann::json> held = candidates[k].held;
        EffectSetFit refined = fit_effect_set({c}, context, &start, &held);
        refine_on_axis(context, refined, candidates[k].screen_profile);
        if (refined.ok) candidates[k] = std::move(refined);
        best_refined_share = std::max(best_refined_share, share_of(context, candidates[k]));
        tried = k + 1;
    }
    std::vector<EffectSetFit> first(candidates.begin(),
                                    candidates.begin() + static_cast<std::ptrdiff_t>(tried));
    restart_nested(context, first, stages);
    for (EffectSetFit& f : first) {
        refine_in_box(context, f, stages);
        walk_valley(context, f, stages);
    }
    restart_nested(context, first, stages);
    std::move(first.begin(), first.end(), candidates.begin());
    std::sort(candidates.begin(), candidates.end(), by_held_out);
    // Ranked by held-out error, and by the information criterion among those within kTieShare of
    // the best.
    prefer_simpler(context, candidates);
    return candidates;
}

}  // namespace scopekin::discrepancy
