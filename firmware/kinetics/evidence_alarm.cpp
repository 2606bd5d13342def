// The evidence alarm's step (evidence_alarm.hpp): the trees' Q16.16 score and a counted debounce.
#include "kinetics/evidence_alarm.hpp"

namespace scopekin::kinetics {

EvidenceAlarm::Outputs EvidenceAlarm::step(const Config& config, const SlackTrees& trees,
                                           const Q16_16 (&features)[kSlackFeatureCount],
                                           State& state) noexcept {
    Outputs out{};
    out.score = SlackRegressor::predict(trees, features);
    out.alarm = debounce(config, out.score, state);
    return out;
}

bool EvidenceAlarm::debounce(const Config& config, Q16_16 score, State& state) noexcept {
    const bool toward_change =
        state.up ? score.raw() < config.clear_score_raw : score.raw() > config.raise_score_raw;
    const std::uint16_t needed = state.up ? config.clear_steps : config.raise_steps;
    state.run = toward_change ? static_cast<std::uint16_t>(state.run + 1U) : std::uint16_t{0};
    if (state.run >= needed) {
        state.up = !state.up;
        state.run = 0;
    }
    return state.up;
}

}  // namespace scopekin::kinetics
