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
/// After sorting by held-out cost: the lowest BIC among those within kTieShare of the best leads
/// (of two effects that explain the same, the one with fewer parameters). A single effect that
/// reduces at its fit to a simpler one also within kTieShare (reduces_to: ei_profile with equal
/// factors is ei_scale) yields to it whatever the BIC: the held-out data do not ask for the
/// extra parameter, and the BIC's sample count overstates the evidence of autocorrelated
/// residuals.
void prefer_simpler(const DiscrepancyContext& context, std::vector<EffectSetFit>& fits);

}  // namespace scopekin::discrepancy
