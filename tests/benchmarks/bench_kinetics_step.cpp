// Speed of the firmware's kinetics::step on the host (a benchmark, not a test): one pass of
// kinetics::init + kinetics::step over a scenario input of tests/firmware/data/scenarios/ (default
// synthetic_insertion_roll: 3200 steps of 5 ms), State and Outputs in static storage as on the
// target.  Reported: time per pass and per step (ns_per_step), steps per pass.  The deterministic
// budget numbers (instructions per step on the Cortex-M4, host Ir under callgrind, RAM, flash,
// stack, heap) come from the `budget` CTest label, never from here.
// Run: build/host/tests/benchmarks/scopekin_bench_kinetics_step
#include <benchmark/benchmark.h>

#include <cstddef>
#include <string_view>

#include "kinetics_harness.hpp"
#include "scenario_registry.hpp"

namespace {

scopekin::kinetics::State g_state;
scopekin::kinetics::Outputs g_outputs;

const scopekin::test_data::Scenario& benchmark_scenario() {
    for (const scopekin::test_data::Scenario* s : scopekin::test_data::all_scenarios) {
        if (std::string_view(s->name) == "synthetic_insertion_roll") {
            return *s;
        }
    }
    return *scopekin::test_data::all_scenarios[0];
}

void BM_KineticsStepScenario(benchmark::State& state) {
    const scopekin::test_data::Scenario& scenario = benchmark_scenario();
    std::size_t steps = 0;
    for (auto _ : state) {
        scopekin::budget::run_scenario(scenario, g_state, g_outputs,
                                       [](std::size_t, const scopekin::kinetics::Outputs& out) {
                                           benchmark::DoNotOptimize(&out);
                                       });
        benchmark::ClobberMemory();
        steps += scenario.step_count;
    }
    state.SetLabel(scenario.name);
    state.counters["steps_per_pass"] = static_cast<double>(scenario.step_count);
    state.counters["ns_per_step"] =
        benchmark::Counter(static_cast<double>(steps) * 1e-9,
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_KineticsStepScenario)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
