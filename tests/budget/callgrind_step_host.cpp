// Host instruction count of kinetics::step under callgrind (reported, never asserted).
//
//   valgrind --tool=callgrind --collect-atstart=no '--toggle-collect=scopekin::kinetics::step(*'
//            scopekin_budget_callgrind_step [--scenario NAME] [--max-steps N]
//
// The program only runs init + step over one scenario (default: the first, by name) and prints
// the number of steps; callgrind collects only inside step (and what step calls), so the total Ir
// divided by the steps is the host's instructions per step.  tests/budget/tools/
// budget_callgrind.py runs it, checks the numbers and writes the budget part.  No wall clock.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <string>

#include "kinetics_harness.hpp"
#include "scenario_registry.hpp"

namespace {
scopekin::kinetics::State g_state;  // static storage, as on the target
scopekin::kinetics::Outputs g_outputs;
}  // namespace

int main(int argc, char** argv) {
    std::string name;
    std::size_t max_steps = 0;  // 0: all
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--scenario" && i + 1 < argc) {
            name = argv[++i];
        } else if (arg == "--max-steps" && i + 1 < argc) {
            max_steps = static_cast<std::size_t>(std::strtoull(argv[++i], nullptr, 10));
        } else {
            std::cerr << "usage: " << argv[0] << " [--scenario NAME] [--max-steps N]\n";
            return 2;
        }
    }
    const scopekin::test_data::Scenario* scenario = scopekin::test_data::all_scenarios[0];
    if (!name.empty()) {
        scenario = nullptr;
        for (const scopekin::test_data::Scenario* s : scopekin::test_data::all_scenarios) {
            if (name == s->name) {
                scenario = s;
            }
        }
        if (scenario == nullptr) {
            std::cerr << "unknown scenario '" << name << "'\n";
            return 2;
        }
    }
    const std::size_t steps =
        max_steps == 0U || max_steps > scenario->step_count ? scenario->step_count : max_steps;

    scopekin::kinetics::init(scopekin::kinetics::default_config(), g_state);
    std::uint32_t sink = 0;
    for (std::size_t i = 0; i < steps; ++i) {
        const scopekin::kinetics::Inputs inputs = scopekin::budget::to_inputs(scenario->steps[i]);
        scopekin::kinetics::step(inputs, g_state, g_outputs);
        sink ^= g_outputs.step_index;
    }
    std::cout << "scenario=" << scenario->name << " steps=" << steps << " sink=" << sink << "\n";
    return 0;
}
