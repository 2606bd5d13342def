// The tip observer's step (tip_observer.hpp). Q16.16 throughout; scaling in the header.
#include "kinetics/tip_observer.hpp"

#include <algorithm>

namespace scopekin::kinetics {

namespace {

constexpr Q16_16 kOne = Q16_16::from_int(1);
constexpr Q16_16 kMmPerMetre = Q16_16::from_int(1000);

/// 1 at or below the free force, 0 at or above the blocked one, linear between
/// (blocked - free >= 1 N: Config::valid).
Q16_16 push_gate(Q16_16 push_N, Q16_16 free_N, Q16_16 blocked_N) noexcept {
    if (!(push_N > free_N)) return kOne;
    if (!(push_N < blocked_N)) return Q16_16{};
    return std::clamp((blocked_N - push_N) / (blocked_N - free_N), Q16_16{}, kOne);
}

/// Inside the colon, within max_ahead_mm ahead of and max_slack_mm behind the depth.
Q16_16 within_bounds(const TipObserver::Config& config, Q16_16 depth_mm, Q16_16 tip_mm) noexcept {
    const Q16_16 lowest = std::max(Q16_16{}, depth_mm - config.max_slack_mm);
    const Q16_16 highest = std::max(lowest, depth_mm + config.max_ahead_mm);
    return std::clamp(tip_mm, lowest, highest);
}

}  // namespace

bool TipObserver::Config::valid() const noexcept {
    const Q16_16 zero{};
    return push_free_N > zero && !(push_blocked_N - push_free_N < kOne) &&
           !(eta_withdrawal < zero) && !(eta_withdrawal > kOne) && !(forget_per_s < zero) &&
           !(max_ahead_mm < zero) && !(max_slack_mm < zero) && !(sigma_floor_mm < zero) &&
           !(sigma_per_depth_mm_per_m < zero) && !(sigma_per_slack < zero);
}

Q16_16 TipObserver::bounded(const Config& config, Q16_16 depth_mm, Q16_16 tip_mm) noexcept {
    return within_bounds(config, depth_mm, tip_mm);
}

Q16_16 TipObserver::reseed(const Config& config, Q16_16 depth_mm, Q16_16 tip_mm,
                           State& state) noexcept {
    state.started = true;
    state.tip_mm = within_bounds(config, depth_mm, tip_mm);
    state.depth_mm = depth_mm;
    return state.tip_mm;
}

TipObserver::Outputs TipObserver::step(const Config& config, const Inputs& inputs,
                                       State& state) noexcept {
    Outputs out{};
    if (!state.started) {
        state.started = true;
        state.tip_mm = std::max(inputs.depth_mm, Q16_16{});
        state.depth_mm = inputs.depth_mm;
    }
    const Q16_16 moved_mm = inputs.depth_mm - state.depth_mm;
    state.depth_mm = inputs.depth_mm;
    const bool advancing = moved_mm > Q16_16{};
    Q16_16 eta = advancing ? kOne : config.eta_withdrawal;
    if (advancing && inputs.force_fresh)
        eta = push_gate(inputs.handle_force_N, config.push_free_N, config.push_blocked_N);
    out.force_evidence = advancing && inputs.force_fresh;

    // Dead reckoning, then the slack forgotten towards the prior (no slack).
    Q16_16 tip = state.tip_mm + eta * moved_mm;
    const Q16_16 forget = std::min(config.forget_per_s * inputs.period_s, kOne);
    tip = tip + forget * (inputs.depth_mm - tip);
    state.tip_mm = within_bounds(config, inputs.depth_mm, tip);

    out.tip_mm = state.tip_mm;
    out.slack_mm = inputs.depth_mm - state.tip_mm;
    out.eta = eta;
    const Q16_16 depth_m = std::max(inputs.depth_mm, Q16_16{}) / kMmPerMetre;
    out.uncertainty_mm = config.sigma_floor_mm + config.sigma_per_depth_mm_per_m * depth_m +
                         config.sigma_per_slack * fixed_point::abs_sat(out.slack_mm);
    return out;
}

}  // namespace scopekin::kinetics
