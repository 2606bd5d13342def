// Placeholder while the reduced model is written (issue 4); replaced by the real estimator.
#include "kinetics/kinetics.hpp"

namespace scopekin::kinetics {

void init(const Config& config, State& state) noexcept {
    state = State{};
    state.config = config;
}

void step(const Inputs& inputs, State& state, Outputs& outputs) noexcept {
    outputs = Outputs{};
    outputs.step_index = state.steps++;
    if ((inputs.fresh_mask & kInsertion) != 0U) state.insertion_mm = inputs.insertion_mm;
    outputs.tip_path_mm = state.insertion_mm;
}

}  // namespace scopekin::kinetics
