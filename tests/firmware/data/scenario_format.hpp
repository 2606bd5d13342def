// scenario_format.hpp — the format of a "scenario input": the per-step Inputs of one run of the
// firmware's kinetics, as plain integer data that compiles on every target (host, aarch64,
// Cortex-M4) with no heap and no floating point.  Documented in tests/firmware/data/README.md.
//
// One scenario = one header tests/firmware/data/scenarios/<name>.hpp that defines, in namespace
// scopekin::test_data::scenarios, exactly
//     inline constexpr ScenarioStep <name>_steps[] = { {...}, ... };
//     inline constexpr Scenario <name>{"<name>", "<one-line description>", 5000U, <name>_steps,
//                                      std::size(<name>_steps)};
// The build globs that directory and generates the registry (all_scenarios(), sorted by name),
// so a scenario is added by dropping a file in; nothing else has to be edited.
#pragma once

#include <cstddef>
#include <cstdint>

namespace scopekin::test_data {

/// One period's handle sensor samples: kinetics::Inputs as raw values.  The four int32 are the
/// raw Q16.16 values (value * 2^16, two's complement) of, in this order, Inputs::handle_force_N,
/// handle_torque_Nmm, insertion_mm and roll_rad; fresh_mask is Inputs::fresh_mask
/// (kinetics::InputSignal bits, other bits allowed: the firmware must ignore or flag them).
struct ScenarioStep {
    std::int32_t handle_force_raw;
    std::int32_t handle_torque_raw;
    std::int32_t insertion_raw;
    std::int32_t roll_raw;
    std::uint8_t fresh_mask;
};

struct Scenario {
    const char* name;         ///< == the file's stem and the C++ identifier
    const char* description;  ///< one line: what the sequence does
    std::uint32_t period_us;  ///< sampling period the steps were generated for
    const ScenarioStep* steps;
    std::size_t step_count;
};

/// Golden value of the cross-target identity check (output_hashes.hpp, generated): FNV-1a 64 of
/// every field of every Outputs of one scenario run through init + step (tests/budget/
/// kinetics_harness.hpp says exactly how).
struct OutputHash {
    const char* scenario;
    std::uint32_t steps;
    std::uint64_t fnv1a64;
};

}  // namespace scopekin::test_data
