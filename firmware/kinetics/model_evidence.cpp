// The model evidence's step (model_evidence.hpp). Q16.16 throughout; scaling in the header.
#include "kinetics/model_evidence.hpp"

#include <algorithm>

namespace scopekin::kinetics {

bool ModelEvidence::Config::valid() const noexcept {
    const Q16_16 zero{};
    const Q16_16 one = Q16_16::from_int(1);
    return !(match_reward < zero) && !(match_reward > one) && mismatch_cost_per_N2 > zero &&
           !(mismatch_cost_per_N2 > one) && limit > zero && !(limit > Q16_16::from_int(1000)) &&
           !(trust_above < fixed_point::neg_sat(limit)) && trust_above < limit &&
           residual_clamp_N > zero && !(residual_clamp_N > Q16_16::from_int(50)) &&
           !(trusted_tip_sd_mm < zero);
}

ModelEvidence::Outputs ModelEvidence::step(const Config& config, const Inputs& inputs,
                                           State& state) noexcept {
    Outputs out{};
    const Q16_16 lowest = fixed_point::neg_sat(config.limit);
    if (!inputs.inside_model) {
        state.log_ratio = lowest;
    } else if (inputs.on_trained_motion && inputs.force_fresh) {
        const Q16_16 residual =
            std::clamp(inputs.handle_force_N - inputs.training_force_N,
                       fixed_point::neg_sat(config.residual_clamp_N), config.residual_clamp_N);
        const Q16_16 increment =
            config.match_reward - config.mismatch_cost_per_N2 * (residual * residual);
        state.log_ratio = std::clamp(state.log_ratio + increment, lowest, config.limit);
        out.residual_N = residual;
        out.evidence = true;
    }
    out.log_ratio = state.log_ratio;
    out.trusted = state.log_ratio > config.trust_above;
    return out;
}

}  // namespace scopekin::kinetics
