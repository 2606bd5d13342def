#pragma once
// How the stages compare fits: the share of the excess error a fit explains, and the order of the
// candidate list.
#include <vector>

#include "host_sim/discrepancy/context.hpp"
#include "host_sim/discrepancy/fit.hpp"

namespace scopekin::discrepancy {

/// Shares of the held-out excess error closer than this count as equal (the BIC decides).
inline constexpr double kTieShare = 0.02;

/// Share of the held-out excess error (cost above the noise floor) a fit removes, in [0, 1].
double share_explained(double cost_before, double cost_after, double floor);
/// A fit's share on the fits' held-out data (the windows, when fitted on windows); 0 if it failed.
double share_of(const DiscrepancyContext& context, const EffectSetFit& fit);
/// Working fits first, then by held-out cost.
bool by_held_out(const EffectSetFit& a, const EffectSetFit& b);
/// What a fit must remove of the held-out excess another leaves to be worth more parameters:
/// kShareOfRest of that excess (cost above the noise floor), and the excess must be kMinRestCost
/// at least (half of one output's noise variance: a plainly visible error, not a fluctuation).
/// The pair rule takes the same share (stage_pairs.cpp).
inline constexpr double kShareOfRest = 0.5;
inline constexpr double kMinRestCost = 0.5;
/// Whether a fit with more parameters (held-out cost `richer_held_out`) removes kShareOfRest of
/// the held-out excess one with fewer leaves (`simpler_held_out` above `noise_floor`), an excess
/// of kMinRestCost or more.
bool earns_its_parameters(double richer_held_out, double simpler_held_out, double noise_floor);

/// A fit's costs: on the held-out blocks and on the training blocks (|normalised residual|^2).
struct NestedCosts {
    double held_out = 0.0;
    double training = 0.0;
};
/// Whether the richer of two nested fits within the tie yields to the simpler: it does not earn
/// its parameters on the held-out data (earns_its_parameters), and it is fitted close to the
/// simpler (`fitted_close`: reduces_to) or the simpler leaves nothing to explain: less than
/// kMinRestCost of held-out excess, and the richer does not earn its parameters on the training
/// blocks either (the same rule on their costs and floor). The held-out blocks are three of ten:
/// where the one phase that shows an effect falls in the training blocks, the held-out data cannot
/// tell the richer from the simpler. (A hidden distal softening 0.9 on procedure B: ei_scale 0.909
/// at held-out 5.48, training 6.64; ei_profile (0.897, 1.022) at 5.31 and 5.07; floors 6 and 6:
/// the profile removes 1.57 of the 0.64 ei_scale leaves in training, and keeps the lead.)
bool richer_yields(NestedCosts richer, NestedCosts simpler, bool fitted_close,
                   double held_out_floor, double training_floor);
/// After sorting by held-out cost: the lowest BIC among those within kTieShare of the best leads
/// (of two effects that explain the same, the one with fewer parameters). Of two nested single
/// effects within kTieShare (ei_profile contains ei_scale): the richer yields to the simpler unless
/// it earns its parameters on the held-out data (earns_its_parameters) when it is fitted close to
/// the simpler (reduces_to: factors within 0.1) or the simpler leaves nothing to explain
/// (richer_yields), whatever the BIC (the BIC's sample count overstates the evidence of
/// autocorrelated residuals); and the simpler yields to a richer one that earns them.
/// (Before: the richer fitted close yielded whatever it earned, and a hidden profile 0.8 to 1.0
/// on procedure B, fitted as (0.81, 0.87), yielded to ei_scale though it removed 63 % of the
/// held-out excess ei_scale left. A richer one fitted far from the simpler kept the lead on its
/// BIC: a hidden EI factor 1.3 on procedure C, ei_scale 1.292 at a held-out cost below the noise
/// floor, and ei_profile (1.28, 1.44), fitted to the training blocks' event timing, was named. And
/// earning alone is no rule for a profile far from uniform: with a second effect still missing,
/// ei_profile (0.61, 0.94) removed 13.2 of the 42 that ei_scale left, 31 %, and was the hidden one.)
void prefer_simpler(const DiscrepancyContext& context, std::vector<EffectSetFit>& fits);

/// Whether a fit of held-out cost `other` explains the held-out data as well as the named set's
/// (`named`): at most kMinRestCost above it, or both less than kMinRestCost above `noise_floor`.
bool explains_as_well(double other, double named, double noise_floor);
/// The other working fits that explain the held-out data as well as `fits[named]`: a held-out cost
/// at most kMinRestCost above the named set's, or both leaving less than kMinRestCost of excess
/// (each explains the recording to its noise). The recording cannot tell them from the named set:
/// the report lists them beside it (a hidden distal softening of 0.9 on procedure C is named
/// ei_scale 0.912, held-out cost 4.13, and ei_profile (0.909, 0.926) reaches 3.95, both under the
/// noise floor of 5). Costs on the fit windows when fitted on windows.
std::vector<std::size_t> equally_consistent(const DiscrepancyContext& context,
                                            const std::vector<EffectSetFit>& fits,
                                            std::size_t named);

}  // namespace scopekin::discrepancy
