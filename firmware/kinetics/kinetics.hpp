// kinetics.hpp — the firmware's kinetic estimator: one call per period.
//
//   init(config, state)          once at start-up (the only place anything is set up)
//   step(inputs, state, outputs) every period (default 5 ms = 200 Hz): pure function of its
//                                arguments, no heap, no static mutable data, fixed work.
#pragma once

#include "kinetics/kinetics_io.hpp"

namespace scopekin::kinetics {

struct Config {
    Q16_16 period_s = Q16_16::from_ratio(1, 200);  ///< step period (5 ms)
};

/// All mutable data of the estimator (Drake-style context).  Sized at compile time.
struct State {
    Config config{};
    std::uint32_t steps{0};
    Q16_16 insertion_mm{};
};

void init(const Config& config, State& state) noexcept;
void step(const Inputs& inputs, State& state, Outputs& outputs) noexcept;

}  // namespace scopekin::kinetics
