// Speed of the world (a benchmark, not a test): the full default colon, the 1.7 m CF-Q160L in
// 1 cm elements (170 elements), h = 10 ms, Gauss-Seidel to 1e-6 N. The scope is advanced at
// 25 mm/s from 20 mm to 520 mm (20 s simulated, 2000 steps), by which time it lies on the wall
// at up to 40 nodes at once. Reported: real-time factor (simulated s per wall-clock s), ms per
// step, contacts and Gauss-Seidel sweeps per step.
// Run: build/host/tests/benchmarks/scopekin_bench_world
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>

#include "model/colon/bundled_colons.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/world/world.hpp"

namespace {
using namespace scopekin::model;

void BM_WorldInsertionDefaultColon(benchmark::State& state) {
    const double simulated_s = static_cast<double>(state.range(0));
    const ColonTube colon = default_colon(cf_q160l::kRadius_mm);
    ScopeSpec scope;
    scope.length_mm = cf_q160l::kWorkingLength_mm;
    scope.elements = 170;
    scope.radius_mm = cf_q160l::kRadius_mm;
    scope.section = cf_q160l::section();
    WorldSettings settings;
    settings.time_step_s = 0.01;
    settings.initial_insertion_mm = 20.0;
    settings.contact.tolerance_N = 1e-6;
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

}  // namespace

BENCHMARK_MAIN();
