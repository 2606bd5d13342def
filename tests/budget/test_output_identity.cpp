// Cross-target bit identity of kinetics::step: the same outputs, bit for bit, on every target.
//
// Every scenario of tests/firmware/data/scenarios/ runs through init + step; every field of every
// Outputs is hashed (FNV-1a 64 over raw integer values, kinetics_harness.hpp) and compared with
// the golden value in tests/firmware/data/output_hashes.hpp.  The same source runs as GoogleTest
// on host, asan and aarch64 and on the Cortex-M4 (QEMU) through portable_check, so all targets
// passing means bit-identical outputs everywhere.
//
// When the estimator changes on purpose, the golden values change: the failing test prints the
// new lines, and `cmake --build build/host --target update_output_hashes` rewrites the header
// (tests/firmware/data/README.md).
#include <cstddef>
#include <cstdint>

#include "decimal_text.hpp"
#include "kinetics_harness.hpp"
#include "output_hashes.hpp"
#include "portable_check.hpp"
#include "scenario_registry.hpp"

#if defined(SCOPEKIN_PORTABLE_CHECK_GTEST)
#include <cstdio>
#endif

namespace {

using scopekin::budget::Fnv1a64;
using scopekin::kinetics::Outputs;
using scopekin::kinetics::Q16_16;
using scopekin::test_data::OutputHash;
using scopekin::test_data::Scenario;

// Static storage: State will grow to tens of KiB (never on the stack).
scopekin::kinetics::State g_state;
Outputs g_outputs;

void print_text(const char* text) noexcept {
#if defined(SCOPEKIN_PORTABLE_CHECK_GTEST)
    std::fputs(text, stdout);
    std::fflush(stdout);
#else
    scopekin::portable_check::write_text(text);
#endif
}

void print_unsigned(std::uint64_t value) noexcept {
    scopekin::portable_check::DecimalBuffer buffer;
    print_text(scopekin::portable_check::decimal_text(value, buffer));
}

const OutputHash* find_golden(const char* scenario) noexcept {
    for (const OutputHash& golden : scopekin::test_data::golden_output_hashes) {
        if (scopekin::budget::same_name(golden.scenario, scenario)) {
            return &golden;
        }
    }
    return nullptr;
}

std::uint64_t hash_of(const Outputs& outputs) noexcept {
    Fnv1a64 hash;
    scopekin::budget::hash_outputs(hash, outputs);
    return hash.value();
}

SCOPEKIN_TEST(OutputIdentity, Fnv1a64MatchesReferenceVectors) {
    // Published FNV-1a 64 test vectors: "" and "a".
    Fnv1a64 empty;
    SCOPEKIN_EXPECT_EQ(empty.value(), 0xCBF29CE484222325ULL);
    Fnv1a64 a;
    a.byte(static_cast<std::uint8_t>('a'));
    SCOPEKIN_EXPECT_EQ(a.value(), 0xAF63DC4C8601EC8CULL);
    // Integers go in least significant byte first: 0x64636261 hashes like "abcd".
    Fnv1a64 word;
    word.u32(0x64636261U);
    Fnv1a64 bytes;
    for (const char c : {'a', 'b', 'c', 'd'}) {
        bytes.byte(static_cast<std::uint8_t>(c));
    }
    SCOPEKIN_EXPECT_EQ(word.value(), bytes.value());
}

SCOPEKIN_TEST(OutputIdentity, EveryFieldOfOutputsChangesTheHash) {
    const Outputs base{};
    const std::uint64_t base_hash = hash_of(base);
    const Q16_16 one = Q16_16::from_raw(1);
    using Mutation = void (*)(Outputs&, Q16_16);
    const Mutation top_level[] = {
        [](Outputs& o, Q16_16) { o.step_index = 1U; },
        [](Outputs& o, Q16_16 v) { o.tip_path_mm = v; },
        [](Outputs& o, Q16_16 v) { o.tip_uncertainty_mm = v; },
        [](Outputs& o, Q16_16 v) { o.tip_velocity_mm_per_s = v; },
        [](Outputs& o, Q16_16 v) { o.model_tip_path_mm = v; },
        [](Outputs& o, Q16_16 v) { o.model_log_likelihood_ratio = v; },
        [](Outputs& o, Q16_16) { o.tip_from_model = true; },
        [](Outputs& o, Q16_16 v) { o.observer_tip_path_mm = v; },
        [](Outputs& o, Q16_16 v) { o.advance_efficiency = v; },
        [](Outputs& o, Q16_16) { o.active_stations = 1U; },
        [](Outputs& o, Q16_16 v) { o.max_contact_force_N = v; },
        [](Outputs& o, Q16_16 v) { o.max_contact_force_uncertainty_N = v; },
        [](Outputs& o, Q16_16 v) { o.model_max_contact_force_N = v; },
        [](Outputs& o, Q16_16) { o.max_contact_station = 1U; },
        [](Outputs& o, Q16_16 v) { o.max_contact_path_mm = v; },
        [](Outputs& o, Q16_16) { o.distal_sticking = 1U; },
        [](Outputs& o, Q16_16) { o.self_lock_alarm = true; },
        [](Outputs& o, Q16_16) { o.model_self_lock_alarm = true; },
        [](Outputs& o, Q16_16 v) { o.loop_score = v; },
        [](Outputs& o, Q16_16) {
            o.contact_force_level = scopekin::kinetics::ContactForceLevel::warning;
        },
        [](Outputs& o, Q16_16) { o.fault_flags = 1U; },
    };
    for (const Mutation mutate : top_level) {
        Outputs changed = base;
        mutate(changed, one);
        SCOPEKIN_EXPECT_TRUE(hash_of(changed) != base_hash);
    }
    // Each field of each station, including the last station.
    for (std::size_t s = 0; s < scopekin::kinetics::kStationCapacity; ++s) {
        for (int field = 0; field < 5; ++field) {
            Outputs changed = base;
            scopekin::kinetics::StationEstimate& station = changed.stations[s];
            switch (field) {
                case 0: station.arc_from_tip_mm = one; break;
                case 1: station.path_position_mm = one; break;
                case 2: station.normal_force_N = one; break;
                case 3: station.tangential_force_N = one; break;
                default: station.state = scopekin::kinetics::StationState::slipping; break;
            }
            SCOPEKIN_EXPECT_TRUE(hash_of(changed) != base_hash);
        }
    }
}

SCOPEKIN_TEST(OutputIdentity, GoldenHashesCoverExactlyTheScenarios) {
    SCOPEKIN_EXPECT_TRUE(scopekin::test_data::scenario_count > 0U);
    for (const Scenario* scenario : scopekin::test_data::all_scenarios) {
        const bool has_golden = find_golden(scenario->name) != nullptr;
        SCOPEKIN_EXPECT_TRUE(has_golden);
        if (!has_golden) {
            print_text("no golden hash for scenario ");
            print_text(scenario->name);
            print_text("\n");
        }
    }
    for (const OutputHash& golden : scopekin::test_data::golden_output_hashes) {
        bool has_scenario = false;
        for (const Scenario* scenario : scopekin::test_data::all_scenarios) {
            has_scenario =
                has_scenario || scopekin::budget::same_name(scenario->name, golden.scenario);
        }
        SCOPEKIN_EXPECT_TRUE(has_scenario);
        if (!has_scenario) {
            print_text("golden hash for a scenario that no longer exists: ");
            print_text(golden.scenario);
            print_text("\n");
        }
    }
}

SCOPEKIN_TEST(OutputIdentity, EveryScenarioMatchesItsGoldenHash) {
    bool any_mismatch = false;
    for (const Scenario* scenario : scopekin::test_data::all_scenarios) {
        const std::uint64_t hash =
            scopekin::budget::hash_scenario_outputs(*scenario, g_state, g_outputs);
        const OutputHash* golden = find_golden(scenario->name);
        const bool match =
            golden != nullptr && golden->steps == scenario->step_count && golden->fnv1a64 == hash;
        char hex[19];
        scopekin::budget::format_hex64(hash, hex);
        print_text(match ? "[ identity ] " : "[ MISMATCH ] ");
        print_text(scenario->name);
        print_text(": ");
        print_unsigned(scenario->step_count);
        print_text(" steps, outputs fnv1a64 ");
        print_text(hex);
        print_text("\n");
        if (!match) {
            any_mismatch = true;
            print_text("    new golden line: {\"");
            print_text(scenario->name);
            print_text("\", ");
            print_unsigned(scenario->step_count);
            print_text("U, ");
            print_text(hex);
            print_text("ULL},\n");
        }
        SCOPEKIN_EXPECT_TRUE(golden != nullptr);
        if (golden != nullptr) {
            SCOPEKIN_EXPECT_EQ(golden->steps, static_cast<std::uint32_t>(scenario->step_count));
            SCOPEKIN_EXPECT_EQ(golden->fnv1a64, hash);
        }
    }
    if (any_mismatch) {
        print_text(
            "If the estimator changed on purpose: cmake --build build/host --target "
            "update_output_hashes (rewrites tests/firmware/data/output_hashes.hpp), then rebuild "
            "and rerun every preset.  If only this target differs: it is not bit-identical.\n");
    }
}

}  // namespace
