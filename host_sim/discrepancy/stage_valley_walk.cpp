// The valley walk for two-parameter fits, a candidate or a pair (stages.hpp, walk_valley).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {
namespace {

/// Points of each round of the search across the valley, and its rounds.
constexpr int kCrossPoints = 7;
constexpr int kCrossRounds = 2;
/// The search across the valley spans ± this many finite-difference steps of the crossing
/// parameter about the valley's predicted floor.
constexpr double kCrossHalfWidthInSteps = 0.4;
/// Steps along the valley per direction at most, and the steps in a row that may rise before the
/// walk in that direction stops.
constexpr int kMaxWalkSteps = 6;
constexpr int kMaxRisingSteps = 2;

struct ValleyPoint {
    std::vector<double> x;
    double cost = std::numeric_limits<double>::infinity();  ///< the fits' training cost
    double chi2 = std::numeric_limits<double>::infinity();  ///< plain chi-square (the SDs')
};

/// A run's plain chi-square on the training blocks.
double chi2_of(const DiscrepancyContext& context, const ModelPrediction& p) {
    return normalised_residuals(context.data, p, context.sigma, SampleSet::fit_training)
        .cwiseProduct(sqrt_counts(context.data, context.sigma, SampleSet::fit_training))
        .squaredNorm();
}

/// Training runs of `fit`'s effect set at each of `points` (its parameters' values, in order).
std::vector<ModelPrediction> training_runs(const DiscrepancyContext& context,
                                           const EffectSetFit& fit,
                                           const std::vector<std::vector<double>>& points) {
    std::vector<nlohmann::json> lists;
    for (const std::vector<double>& x : points)
        lists.push_back(entries_of(fit, x));
    return context.evaluator.run_all(lists, RunScope::fit_training);
}

/// Training runs at `points`; the lowest (infinite cost when every run failed).
ValleyPoint lowest_of(const DiscrepancyContext& context, const EffectSetFit& fit,
                      const std::vector<std::vector<double>>& points) {
    const std::vector<ModelPrediction> runs = training_runs(context, fit, points);
    ValleyPoint lowest;
    for (std::size_t k = 0; k < runs.size(); ++k) {
        if (!runs[k].ok) continue;
        const double cost = context.residuals(runs[k], SampleSet::fit_training).squaredNorm();
        if (cost < lowest.cost) lowest = {points[k], cost, chi2_of(context, runs[k])};
    }
    return lowest;
}

/// The valley's floor where parameter `along` is `at`: kCrossRounds rounds of kCrossPoints runs of
/// the other parameter inside ± kCrossHalfWidthInSteps of its step about `centre`, each round
/// around the best so far.
ValleyPoint cross_valley(const DiscrepancyContext& context, const EffectSetFit& fit,
                         const std::vector<FittedParameter>& params, std::size_t along, double at,
                         double centre) {
    const std::size_t across = 1 - along;
    const FittedParameter& p = params[across];
    double half = kCrossHalfWidthInSteps * p.step;
    ValleyPoint best;
    for (int round = 0; round < kCrossRounds; ++round) {
        std::vector<std::vector<double>> points;
        for (int k = 0; k < kCrossPoints; ++k) {
            std::vector<double> x(2);
            x[along] = at;
            x[across] = std::clamp(centre - half + 2.0 * half * k / (kCrossPoints - 1), p.lo, p.hi);
            points.push_back(std::move(x));
        }
        const ValleyPoint round_best = lowest_of(context, fit, points);
        if (round_best.cost < best.cost) best = round_best;
        if (!std::isfinite(best.cost)) return best;
        centre = best.x[across];
        half /= (kCrossPoints - 1) / 2.0;
    }
    return best;
}

/// The parameter the training cost changes least along: the fit moved one finite-difference step
/// either way in each (4 runs).
std::size_t weaker_parameter(const DiscrepancyContext& context, const EffectSetFit& fit,
                             const std::vector<FittedParameter>& params) {
    std::vector<std::vector<double>> points;
    for (std::size_t j = 0; j < 2; ++j)
        for (double sign : {-1.0, 1.0}) {
            std::vector<double> x = fit.values;
            const FittedParameter& p = params[j];
            x[j] = std::clamp(x[j] + sign * p.step, p.lo, p.hi);
            points.push_back(std::move(x));
        }
    const std::vector<ModelPrediction> runs = training_runs(context, fit, points);
    double rise[2] = {0.0, 0.0};
    for (std::size_t k = 0; k < runs.size(); ++k)
        rise[k / 2] += runs[k].ok
                           ? context.residuals(runs[k], SampleSet::fit_training).squaredNorm() -
                                 fit.training_cost
                           : std::numeric_limits<double>::infinity();
    return rise[1] < rise[0] ? 1 : 0;
}

/// One direction of the walk from `start`: steps of parameter `along` by its finite-difference
/// step, the other predicted by the valley's slope so far and searched across (cross_valley).
/// Appends the floor points to `profile`; returns the lowest.
ValleyPoint walk_one_way(const DiscrepancyContext& context, const EffectSetFit& fit,
                         const std::vector<FittedParameter>& params, std::size_t along,
                         double direction, const ValleyPoint& start,
                         nlohmann::ordered_json& profile) {
    const std::size_t across = 1 - along;
    const FittedParameter& q = params[along];
    const double step = direction * q.step;
    ValleyPoint previous = start, best = start;
    double slope = 0.0;  // d(across)/d(along) on the floor
    int rising = 0;
    for (int s = 0; s < kMaxWalkSteps; ++s) {
        const double at = previous.x[along] + step;
        if (at < q.lo || at > q.hi) break;
        const ValleyPoint floor =
            cross_valley(context, fit, params, along, at, previous.x[across] + slope * step);
        if (!std::isfinite(floor.cost)) break;
        profile.push_back(
            {{"values", floor.x}, {"training_cost", floor.cost}, {"training_chi2", floor.chi2}});
        slope = (floor.x[across] - previous.x[across]) / step;
        if (floor.cost < best.cost) {
            best = floor;
            rising = 0;
        } else if (++rising == kMaxRisingSteps) {
            break;
        }
        previous = floor;
    }
    return best;
}

/// The walk's lowest floor point narrowed down: the floor searched at half and a quarter of the
/// walk's step either side of the best so far (4 more cross_valley searches). Appends them to
/// `profile`; returns the lowest.
ValleyPoint narrow_down(const DiscrepancyContext& context, const EffectSetFit& fit,
                        const std::vector<FittedParameter>& params, std::size_t along,
                        ValleyPoint best, nlohmann::ordered_json& profile) {
    const FittedParameter& q = params[along];
    for (double fraction : {0.5, 0.25}) {
        const ValleyPoint centre = best;
        for (double direction : {-1.0, 1.0}) {
            const double at = centre.x[along] + direction * fraction * q.step;
            if (at < q.lo || at > q.hi) continue;
            const ValleyPoint floor =
                cross_valley(context, fit, params, along, at, centre.x[1 - along]);
            if (!std::isfinite(floor.cost)) continue;
            profile.push_back({{"values", floor.x},
                               {"training_cost", floor.cost},
                               {"training_chi2", floor.chi2}});
            if (floor.cost < best.cost) best = floor;
        }
    }
    return best;
}

}  // namespace

void walk_valley(const DiscrepancyContext& context, EffectSetFit& fit, StageLog& stages) {
    if (context.evaluator.windowed()) return;  // long runs: the 10-minute recording's budget
    const std::vector<FittedParameter> params = two_screened_parameters(fit);
    if (params.empty()) return;
    stages.start("walking " + set_name(fit) + "'s valley",
                 (2.0 + static_cast<double>(kRefined)) / kProgressSteps);
    const std::size_t along = weaker_parameter(context, fit, params);
    const ValleyPoint start{fit.values, fit.training_cost, chi2_of(context, fit.prediction)};
    nlohmann::ordered_json profile = nlohmann::ordered_json::array();
    profile.push_back({{"values", fit.values},
                       {"training_cost", fit.training_cost},
                       {"training_chi2", start.chi2}});
    ValleyPoint best = start;
    for (double direction : {1.0, -1.0}) {
        const ValleyPoint found =
            walk_one_way(context, fit, params, along, direction, start, profile);
        if (found.cost < best.cost) best = found;
    }
    // At the noise floor the walk's steps still measure the valley's width (the SD); narrowing
    // down could only move the fit within the noise.
    if (leaves_training_excess(best.cost, context.training_noise_floor()))
        best = narrow_down(context, fit, params, along, best, profile);
    std::sort(profile.begin(), profile.end(), [&](const auto& a, const auto& b) {
        return a["values"][along].template get<double>() <
               b["values"][along].template get<double>();
    });
    nlohmann::ordered_json walk = {
        {"along", params[along].key}, {"from", fit.values}, {"floor", profile}};
    if (best.cost < fit.training_cost) {
        EffectSetFit there = fit_effect_set(fit.candidates, context, &best.x, &fit.held);
        if (there.ok && there.training_cost < fit.training_cost) {
            there.iterations = fit.iterations;
            fit = std::move(there);
        }
    }
    walk["to"] = fit.values;
    fit.valley_walk = std::move(walk);
}

}  // namespace scopekin::discrepancy
