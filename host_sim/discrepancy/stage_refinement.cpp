#include <algorithm>

#include "host_sim/discrepancy/ranking.hpp"
#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {
namespace {

/// A runner-up whose screening step comes this close to the refined best is refined too.
constexpr double kRefineNear = 0.1;

}  // namespace

std::vector<EffectSetFit> refine_candidates(const DiscrepancyContext& context,
                                            const std::vector<EffectSetFit>& screened,
                                            StageLog& stages) {
    std::vector<EffectSetFit> candidates = screened;
    std::sort(candidates.begin(), candidates.end(), by_held_out);
    // The best single effect; the next one while the refined ones explain too little, or when its
    // screening step came as close as kRefineNear (two effects that explain the same: ei_profile
    // with equal factors is ei_scale). Never one whose screening explained nothing.
    double best_refined_share = 0.0;
    for (std::size_t k = 0; k < std::min(kRefined, candidates.size()); ++k) {
        if (!candidates[k].ok) continue;
        if (k > 0 && !(share_of(context, candidates[k]) > 0.0)) break;
        if (k > 0 && best_refined_share >= context.options.min_share &&
            share_of(context, candidates[k]) < best_refined_share - kRefineNear)
            break;
        const std::size_t c = candidates[k].candidates[0];
        stages.start("fitting " + candidate_library()[c].name,
                     (2.0 + static_cast<double>(k)) / kProgressSteps);
        const std::vector<double> start = candidates[k].values;
        const std::vector<nlohmann::json> held = candidates[k].held;
        EffectSetFit refined = fit_effect_set({c}, context, &start, &held);
        if (refined.ok) candidates[k] = std::move(refined);
        best_refined_share = std::max(best_refined_share, share_of(context, candidates[k]));
    }
    std::sort(candidates.begin(), candidates.end(), by_held_out);
    // Ranked by held-out error, and by the information criterion among those within kTieShare of
    // the best.
    prefer_simpler(context, candidates);
    return candidates;
}

}  // namespace scopekin::discrepancy
