// slack_excess.cpp — the truth's pace rule on the tracker's odometry (see the header).
#include "kinetics/slack_excess.hpp"

#include <algorithm>

namespace scopekin::kinetics {
namespace {

using fixed_point::mul_sat;
using fixed_point::sub_sat;

/// L = insertion - travel [mm]: the scope taken up between the hand and the tip, up to a constant.
Q16_16 taken_up(const SlackExcess::Sample& s) noexcept {
    return sub_sat(s.insertion_mm, s.travel_mm);
}

const SlackExcess::Sample& at(const SlackExcess::State& state, std::size_t i) noexcept {
    return state.ring[(state.oldest + i) % SlackExcess::kCapacity];
}

void push(SlackExcess::State& state, const SlackExcess::Sample& sample) noexcept {
    if (state.count == SlackExcess::kCapacity) {  // never with a valid config: drop the oldest
        state.oldest = (state.oldest + 1) % SlackExcess::kCapacity;
        --state.count;
    }
    state.ring[(state.oldest + state.count) % SlackExcess::kCapacity] = sample;
    ++state.count;
}

/// Keeps the poses of the last window_steps periods (the newest always stays).
void prune(SlackExcess::State& state, std::uint32_t now, std::uint16_t window_steps) noexcept {
    while (state.count > 1U && now - at(state, 0).step > window_steps) {  // bound: kCapacity
        state.oldest = (state.oldest + 1) % SlackExcess::kCapacity;
        --state.count;
    }
}

Q16_16 least_taken_up(const SlackExcess::State& state) noexcept {
    Q16_16 least = taken_up(at(state, 0));
    for (std::size_t i = 1; i < state.count; ++i) {  // bound: kCapacity
        least = std::min(least, taken_up(at(state, i)));
    }
    return least;
}

SlackExcess::Outputs outputs_of(const SlackExcess::Config& config,
                                const SlackExcess::State& state) noexcept {
    SlackExcess::Outputs out{};
    out.valid = state.started;
    out.excess_mm = state.excess_mm;
    out.gate_open = state.started && !(state.excess_mm < config.gate_mm);
    return out;
}

}  // namespace

bool SlackExcess::Config::valid() const noexcept {
    return window_steps >= 1U && window_steps < kCapacity && min_hand_mm > Q16_16{} &&
           pace_fraction > Q16_16{} && !(pace_fraction > Q16_16::from_int(1)) &&
           !(gate_mm < Q16_16{});
}

SlackExcess::Outputs SlackExcess::step(const Config& config, const Inputs& in,
                                       State& state) noexcept {
    if (!in.active) {
        if (state.started) state = State{};  // the ring is cleared once, not every period
        return Outputs{};
    }
    if (!in.fresh) return outputs_of(config, state);
    const Sample now{in.step, in.insertion_mm, in.travel_mm};
    push(state, now);
    prune(state, in.step, config.window_steps);
    const Sample& first = at(state, 0);
    const Q16_16 hand_mm = sub_sat(now.insertion_mm, first.insertion_mm);
    const Q16_16 tip_mm = sub_sat(now.travel_mm, first.travel_mm);
    const bool keeps_pace =
        !(hand_mm < config.min_hand_mm) && !(tip_mm < mul_sat(config.pace_fraction, hand_mm));
    const Q16_16 current = taken_up(now);
    if (!state.started) {
        state.started = true;
        state.base_mm = current;
    }
    state.base_mm = keeps_pace ? least_taken_up(state) : std::min(state.base_mm, current);
    state.excess_mm = sub_sat(current, state.base_mm);
    return outputs_of(config, state);
}

}  // namespace scopekin::kinetics
