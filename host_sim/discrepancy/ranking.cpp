#include "host_sim/discrepancy/ranking.hpp"

#include <algorithm>

namespace scopekin::discrepancy {

double share_explained(double cost_before, double cost_after, double floor) {
    const double excess = cost_before - floor;
    if (!(excess > 0.0)) return 0.0;
    return std::clamp((cost_before - cost_after) / excess, 0.0, 1.0);
}

double share_of(const DiscrepancyContext& context, const EffectSetFit& fit) {
    return fit.ok ? share_explained(context.cost_before_fit, fit.held_out_cost, context.noise_floor)
                  : 0.0;
}

bool by_held_out(const EffectSetFit& a, const EffectSetFit& b) {
    if (a.ok != b.ok) return a.ok;
    return a.held_out_cost < b.held_out_cost;
}

void prefer_simpler(const DiscrepancyContext& context, std::vector<EffectSetFit>& fits) {
    if (fits.empty() || !fits.front().ok) return;
    std::size_t lead = 0;
    for (std::size_t k = 1; k < fits.size(); ++k)
        if (fits[k].ok &&
            share_of(context, fits[k]) >= share_of(context, fits.front()) - kTieShare &&
            fits[k].bic < fits[lead].bic)
            lead = k;
    // A nested effect at the point where it is the simpler one yields to it.
    for (bool yielded = true; yielded;) {
        yielded = false;
        if (fits[lead].candidates.size() != 1) break;
        for (std::size_t k = 0; k < fits.size(); ++k)
            if (k != lead && fits[k].ok && fits[k].candidates.size() == 1 &&
                share_of(context, fits[k]) >= share_of(context, fits.front()) - kTieShare &&
                reduces_to(fits[lead].candidates[0], fits[lead].values, fits[k].candidates[0])) {
                lead = k;
                yielded = true;
                break;
            }
    }
    std::rotate(fits.begin(), fits.begin() + static_cast<std::ptrdiff_t>(lead),
                fits.begin() + static_cast<std::ptrdiff_t>(lead) + 1);
}

}  // namespace scopekin::discrepancy
