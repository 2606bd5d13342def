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

bool earns_its_parameters(double richer_held_out, double simpler_held_out, double noise_floor) {
    const double rest = simpler_held_out - noise_floor;
    return rest >= kMinRestCost && simpler_held_out - richer_held_out >= kShareOfRest * rest;
}

namespace {

/// Whether single-effect fit `a` contains single-effect fit `b` (ei_profile contains ei_scale).
bool contains(const EffectSetFit& a, const EffectSetFit& b) {
    return a.candidates.size() == 1 && b.candidates.size() == 1 &&
           !nested_start(a.candidates[0], b.candidates[0], b.values).empty();
}

NestedCosts costs_of(const EffectSetFit& f) {
    return {f.held_out_cost, f.training_cost};
}

}  // namespace

bool richer_yields(NestedCosts richer, NestedCosts simpler, bool fitted_close,
                   double held_out_floor, double training_floor) {
    if (earns_its_parameters(richer.held_out, simpler.held_out, held_out_floor)) return false;
    const bool leaves_nothing =
        simpler.held_out - held_out_floor < kMinRestCost &&
        !earns_its_parameters(richer.training, simpler.training, training_floor);
    return fitted_close || leaves_nothing;
}

void prefer_simpler(const DiscrepancyContext& context, std::vector<EffectSetFit>& fits) {
    if (fits.empty() || !fits.front().ok) return;
    const double tie = share_of(context, fits.front()) - kTieShare;
    const double training_floor = context.training_noise_floor();
    std::size_t lead = 0;
    for (std::size_t k = 1; k < fits.size(); ++k)
        if (fits[k].ok && share_of(context, fits[k]) >= tie && fits[k].bic < fits[lead].bic)
            lead = k;
    // Of two nested effects within the tie: the richer yields to the simpler (richer_yields)
    // whatever the BIC; the simpler yields to the richer that earns its parameters.
    for (bool moved = true; moved;) {
        moved = false;
        for (std::size_t k = 0; k < fits.size() && !moved; ++k) {
            if (k == lead || !fits[k].ok || share_of(context, fits[k]) < tie) continue;
            const bool to_simpler =
                contains(fits[lead], fits[k]) &&
                richer_yields(
                    costs_of(fits[lead]), costs_of(fits[k]),
                    reduces_to(fits[lead].candidates[0], fits[lead].values, fits[k].candidates[0]),
                    context.noise_floor, training_floor);
            const bool to_richer =
                contains(fits[k], fits[lead]) &&
                earns_its_parameters(fits[k].held_out_cost, fits[lead].held_out_cost,
                                     context.noise_floor);
            if (to_simpler || to_richer) {
                lead = k;
                moved = true;
            }
        }
    }
    std::rotate(fits.begin(), fits.begin() + static_cast<std::ptrdiff_t>(lead),
                fits.begin() + static_cast<std::ptrdiff_t>(lead) + 1);
}

bool explains_as_well(double other, double named, double noise_floor) {
    const bool both_to_noise =
        named - noise_floor < kMinRestCost && other - noise_floor < kMinRestCost;
    return other <= named + kMinRestCost || both_to_noise;
}

std::vector<std::size_t> equally_consistent(const DiscrepancyContext& context,
                                            const std::vector<EffectSetFit>& fits,
                                            std::size_t named) {
    std::vector<std::size_t> equals;
    for (std::size_t k = 0; k < fits.size(); ++k)
        if (k != named && fits[k].ok &&
            explains_as_well(fits[k].held_out_cost, fits[named].held_out_cost, context.noise_floor))
            equals.push_back(k);
    return equals;
}

}  // namespace scopekin::discrepancy
