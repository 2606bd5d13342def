// kinetics_harness.hpp — what every budget/identity program shares: scenario steps -> Inputs, the
// field-by-field FNV-1a 64 hash of Outputs, and the init+step loop over one scenario.
//
// Only kinetics::init / kinetics::step / the I/O structs are used (never a field of State or
// Config), so the harness keeps working when the estimator and its State are replaced.  State
// is always passed in by the caller, who keeps it in static storage (it will be 10-30 KiB).
// Header-only, no heap, no floating point, no exceptions: it builds with the firmware flags on
// bare metal too.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "kinetics/default_reduced_tables.hpp"
#include "kinetics/kinetics.hpp"
#include "scenario_format.hpp"

namespace scopekin::budget {

using test_data::Scenario;
using test_data::ScenarioStep;

[[nodiscard]] inline kinetics::Inputs to_inputs(const ScenarioStep& step) noexcept {
    kinetics::Inputs inputs{};
    inputs.handle_force_N = kinetics::Q16_16::from_raw(step.handle_force_raw);
    inputs.handle_torque_Nmm = kinetics::Q16_16::from_raw(step.handle_torque_raw);
    inputs.insertion_mm = kinetics::Q16_16::from_raw(step.insertion_raw);
    inputs.roll_rad = kinetics::Q16_16::from_raw(step.roll_raw);
    inputs.fresh_mask = step.fresh_mask;
    return inputs;
}

// --- FNV-1a 64 over raw integer values ----------------------------------------------------------
//
// Every field is fed as its integer value, least significant byte first, with a fixed width
// (uint32/int32/Q16_16 raw: 4 bytes; uint8, bool (0/1), one-byte enums: 1 byte).  Struct padding
// never enters the hash, and neither do the host's byte order or the compiler's layout.

class Fnv1a64 {
public:
    static constexpr std::uint64_t offset_basis = 0xCBF29CE484222325ULL;
    static constexpr std::uint64_t prime = 0x00000100000001B3ULL;

    constexpr void byte(std::uint8_t value) noexcept {
        hash_ ^= value;
        hash_ *= prime;
    }
    constexpr void u8(std::uint8_t value) noexcept { byte(value); }
    constexpr void u32(std::uint32_t value) noexcept {
        for (unsigned shift = 0U; shift < 32U; shift += 8U) {  // bound: 4 bytes
            byte(static_cast<std::uint8_t>((value >> shift) & 0xFFU));
        }
    }
    constexpr void i32(std::int32_t value) noexcept { u32(static_cast<std::uint32_t>(value)); }
    constexpr void q16(kinetics::Q16_16 value) noexcept { i32(value.raw()); }
    constexpr void boolean(bool value) noexcept { u8(value ? 1U : 0U); }
    template <typename Enum>
    constexpr void enumeration(Enum value) noexcept {
        static_assert(std::is_enum_v<Enum> && sizeof(Enum) == 1U, "one-byte enums only");
        u8(static_cast<std::uint8_t>(value));
    }

    [[nodiscard]] constexpr std::uint64_t value() const noexcept { return hash_; }

private:
    std::uint64_t hash_{offset_basis};
};

// --- guard: every field of Outputs is hashed ----------------------------------------------------
//
// Counts the members of an aggregate (the largest n for which T{x1, ..., xn} compiles with
// placeholders convertible to anything).  When Outputs, StationEstimate or Inputs gain or lose a
// member, the static_asserts below stop the build until hash_outputs / to_inputs are updated.
namespace detail {

struct AnyField {
    template <typename T>
    operator T() const noexcept;  // declared only: used in unevaluated operands
};

template <typename T, std::size_t... I>
constexpr bool brace_initialisable(std::index_sequence<I...> /*unused*/) noexcept {
    return requires {
        T{(static_cast<void>(I), AnyField{})...};
    };
}

template <typename T, std::size_t N = 0>
constexpr std::size_t aggregate_field_count() noexcept {
    if constexpr (N < 64U && brace_initialisable<T>(std::make_index_sequence<N + 1U>{})) {
        return aggregate_field_count<T, N + 1U>();
    } else {
        return N;
    }
}

}  // namespace detail

static_assert(detail::aggregate_field_count<kinetics::Outputs>() == 24U,
              "kinetics::Outputs changed: hash every field in hash_outputs(), then update this "
              "count and regenerate the golden hashes (tests/firmware/data/README.md)");
static_assert(detail::aggregate_field_count<kinetics::StationEstimate>() == 5U,
              "kinetics::StationEstimate changed: hash every field in hash_outputs()");
// Inputs::tracker (the test bench's EM tracker and tip force) stays zero in every scenario: these
// are the box as used in a patient, without the bench's tracker. The tip odometer that reads it
// (tip_odometer.hpp) is checked value by value on every ISA by test_tip_odometer.cpp.
static_assert(
    detail::aggregate_field_count<kinetics::Inputs>() == 6U,
    "kinetics::Inputs changed: extend ScenarioStep (scenario_format.hpp) and to_inputs()");

/// Feeds every field of `outputs`, in declaration order, into `hash`.
constexpr void hash_outputs(Fnv1a64& hash, const kinetics::Outputs& outputs) noexcept {
    hash.u32(outputs.step_index);
    hash.q16(outputs.tip_path_mm);
    hash.q16(outputs.tip_uncertainty_mm);
    hash.q16(outputs.tip_velocity_mm_per_s);
    hash.q16(outputs.model_tip_path_mm);
    hash.q16(outputs.model_log_likelihood_ratio);
    hash.boolean(outputs.tip_from_model);
    hash.boolean(outputs.tip_from_tracker);
    hash.q16(outputs.observer_tip_path_mm);
    hash.q16(outputs.advance_efficiency);
    for (const kinetics::StationEstimate& station : outputs.stations) {  // bound: kStationCapacity
        hash.q16(station.arc_from_tip_mm);
        hash.q16(station.path_position_mm);
        hash.q16(station.normal_force_N);
        hash.q16(station.tangential_force_N);
        hash.enumeration(station.state);
    }
    hash.u8(outputs.active_stations);
    hash.q16(outputs.max_contact_force_N);
    hash.q16(outputs.max_contact_force_uncertainty_N);
    hash.q16(outputs.model_max_contact_force_N);
    hash.u8(outputs.max_contact_station);
    hash.q16(outputs.max_contact_path_mm);
    hash.u8(outputs.distal_sticking);
    hash.boolean(outputs.self_lock_alarm);
    hash.boolean(outputs.model_self_lock_alarm);
    hash.q16(outputs.loop_score);
    hash.enumeration(outputs.contact_force_level);
    hash.enumeration(outputs.model_contact_force_level);
    hash.u32(outputs.fault_flags);
}

// --- one scenario through init + step -----------------------------------------------------------

/// init(default_config(), state), then step() once per scenario step; after each step calls
/// `after_step(step_number, outputs)`.  `state` and `outputs` belong to the caller (static).
template <typename AfterStep>
void run_scenario(const Scenario& scenario, kinetics::State& state, kinetics::Outputs& outputs,
                  AfterStep&& after_step) noexcept {
    kinetics::init(kinetics::default_config(), state);
    for (std::size_t i = 0; i < scenario.step_count; ++i) {  // bound: the scenario's length
        const kinetics::Inputs inputs = to_inputs(scenario.steps[i]);
        kinetics::step(inputs, state, outputs);
        after_step(i, outputs);
    }
}

/// FNV-1a 64 of every field of every Outputs of the scenario, in step order.
[[nodiscard]] inline std::uint64_t hash_scenario_outputs(const Scenario& scenario,
                                                         kinetics::State& state,
                                                         kinetics::Outputs& outputs) noexcept {
    Fnv1a64 hash;
    run_scenario(scenario, state, outputs,
                 [&hash](std::size_t, const kinetics::Outputs& out) { hash_outputs(hash, out); });
    return hash.value();
}

/// Plain C-string equality (no <cstring> dependency on bare metal).
[[nodiscard]] constexpr bool same_name(const char* a, const char* b) noexcept {
    for (std::size_t i = 0; i < 256U; ++i) {  // bound: names are short identifiers
        if (a[i] != b[i]) {
            return false;
        }
        if (a[i] == '\0') {
            return true;
        }
    }
    return false;
}

/// Writes `value` as "0x" + 16 upper-case hex digits + NUL into `text`.
inline void format_hex64(std::uint64_t value, char (&text)[19]) noexcept {
    constexpr char digits[] = "0123456789ABCDEF";
    text[0] = '0';
    text[1] = 'x';
    for (std::size_t i = 0; i < 16U; ++i) {
        text[2U + i] = digits[(value >> (60U - 4U * i)) & 0xFU];
    }
    text[18] = '\0';
}

}  // namespace scopekin::budget
