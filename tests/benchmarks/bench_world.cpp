// Speed of the world (a benchmark, not a test): the full default colon, the 1.7 m CF-Q160L in
// 1 cm elements (170 elements), h = 10 ms, Gauss-Seidel to 1e-6 N. The scope is advanced at
// 25 mm/s from 20 mm to 520 mm (20 s simulated, 2000 steps), by which time it lies on the wall
// at up to 40 nodes at once. Reported: real-time factor (simulated s per wall-clock s), ms per
// step, contacts and Gauss-Seidel sweeps per step. A second benchmark runs the demo's loop and its
// reduction with and without telescoping (below).
// Run: build/host/tests/benchmarks/scopekin_bench_world
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "model/colon/bundled_colons.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/world/world.hpp"

namespace {
using namespace scopekin::model;

/// The CF-Q160L, 1.7 m in 1 cm elements (170 elements).
ScopeSpec benchmark_scope() {
    ScopeSpec scope;
    scope.length_mm = cf_q160l::kWorkingLength_mm;
    scope.elements = 170;
    scope.radius_mm = cf_q160l::kRadius_mm;
    scope.section = cf_q160l::section();
    return scope;
}

/// h = 10 ms, 20 mm inserted at the start, Gauss-Seidel to 1e-6 N.
WorldSettings benchmark_settings() {
    WorldSettings settings;
    settings.time_step_s = 0.01;
    settings.initial_insertion_mm = 20.0;
    settings.contact.tolerance_N = 1e-6;
    return settings;
}

void BM_WorldInsertionDefaultColon(benchmark::State& state) {
    const double simulated_s = static_cast<double>(state.range(0));
    const ColonTube colon = default_colon(cf_q160l::kRadius_mm);
    const ScopeSpec scope = benchmark_scope();
    const WorldSettings settings = benchmark_settings();
    std::size_t steps = 0, max_contacts = 0, sweeps = 0, max_sweeps = 0, fallbacks = 0;
    for (auto _ : state) {
        state.PauseTiming();
        World world(scope, colon, default_colon_properties(), settings);
        state.ResumeTiming();
        HandleCommand command;
        const auto n = static_cast<std::size_t>(simulated_s / settings.time_step_s);
        for (std::size_t i = 0; i < n; ++i) {
            command.insertion_mm = settings.initial_insertion_mm +
                                   25.0 * settings.time_step_s * static_cast<double>(i + 1);
            const WorldStepReport r = world.step(command);
            if (!r.ok) {
                state.SkipWithError(r.failure.c_str());
                return;
            }
            ++steps;
            max_contacts = std::max(max_contacts, r.contacts);
            sweeps += r.sweeps;
            max_sweeps = std::max(max_sweeps, r.sweeps);
            fallbacks += r.material_tangent_fallback ? 1U : 0U;
        }
    }
    const double per_run = static_cast<double>(steps) / static_cast<double>(state.iterations());
    state.counters["simulated_s_per_run"] = simulated_s;
    state.counters["steps"] = per_run;
    state.counters["realtime_factor"] = benchmark::Counter(
        simulated_s * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["ms_per_step"] =
        benchmark::Counter(static_cast<double>(steps) * 1e-3,
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
    state.counters["max_contacts"] = static_cast<double>(max_contacts);
    state.counters["mean_sweeps"] = static_cast<double>(sweeps) / static_cast<double>(steps);
    state.counters["max_sweeps"] = static_cast<double>(max_sweeps);
    state.counters["tangent_fallbacks"] = static_cast<double>(fallbacks);
}
// Argument: simulated seconds (20 s: the insertion to 520 mm with up to 40 contacts).
BENCHMARK(BM_WorldInsertionDefaultColon)->Arg(20)->Iterations(1)->Unit(benchmark::kMillisecond);
// Short run for the smoke test.
BENCHMARK(BM_WorldInsertionDefaultColon)->Arg(1)->Iterations(1)->Unit(benchmark::kMillisecond);

// The demo's loop and its reduction with the colon telescoping (model/README.md, "Telescoping"):
// advance at 20 mm/s from 20 mm for 33 s (an N-loop grows in the sigmoid), hold 0.5 s, roll 90
// degrees in 2 s, withdraw at 15 mm/s for 15 s (the sigmoid pleats onto the scope): 50.5 s
// simulated, no abdominal pressure. Reported as the insertion benchmark, plus the sigmoid's pleated
// fraction at the end.
void BM_WorldLoopReductionTelescoping(benchmark::State& state) {
    const ColonTube colon = default_colon(cf_q160l::kRadius_mm);
    const ScopeSpec scope = benchmark_scope();
    WorldSettings settings = benchmark_settings();
    settings.telescoping.enabled = state.range(0) != 0;
    const double h = settings.time_step_s;
    const auto steps = static_cast<std::size_t>(std::lround(50.5 / h));
    std::size_t max_contacts = 0;
    double pleated = 0.0;
    for (auto _ : state) {
        state.PauseTiming();
        World world(scope, colon, default_colon_properties(), settings);
        state.ResumeTiming();
        HandleCommand command;
        for (std::size_t i = 1; i <= steps; ++i) {
            const double t = h * static_cast<double>(i);
            command.insertion_mm =
                20.0 + 20.0 * std::min(t, 33.0) - 15.0 * std::clamp(t - 35.5, 0.0, 15.0);
            command.roll_rad = std::clamp(t - 33.5, 0.0, 2.0) * 0.25 * M_PI;
            const WorldStepReport r = world.step(command);
            if (!r.ok) {
                state.SkipWithError(r.failure.c_str());
                return;
            }
            max_contacts = std::max(max_contacts, r.contacts);
        }
        pleated = world.telescoping().state().fraction.at(0);
    }
    state.counters["simulated_s_per_run"] = 50.5;
    state.counters["realtime_factor"] = benchmark::Counter(
        50.5 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["max_contacts"] = static_cast<double>(max_contacts);
    state.counters["sigmoid_pleated_fraction"] = pleated;
}
// Argument: telescoping on (1) or off (0, the same hands in a colon that cannot pleat).
BENCHMARK(BM_WorldLoopReductionTelescoping)
    ->Arg(1)
    ->Arg(0)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
