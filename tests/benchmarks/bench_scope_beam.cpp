// Speed of the reference model (a benchmark, not a test): one implicit dynamic step and one
// static Newton iteration of a 1.7 m CF-Q160L in 1 cm elements (170 elements, 1026 DOF).
// Run: build/host/tests/benchmarks/scopekin_bench_scope_beam
#include <benchmark/benchmark.h>

#include <cmath>

#include "model/beam/scope_beam.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/solvers/dynamic_solver.hpp"
#include "model/solvers/newton_system.hpp"
#include "model/solvers/rayleigh_damping.hpp"

namespace {
using namespace scopekin::model;

constexpr std::size_t kElements = 170;

/// The 1.7 m scope in `elements` equal elements (170 = 1 cm elements).
ScopeBeam make_scope(std::size_t elements = kElements) {
    return straight_beam(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                         cf_q160l::kWorkingLength_mm, elements, cf_q160l::section());
}

// The scope held at the handle (node 0), falling and swinging under gravity: every step does
// real large-rotation Newton work (typically 2-4 iterations).
void BM_DynamicStep(benchmark::State& state) {
    ScopeBeam scope = make_scope();
    DynamicSettings settings;
    settings.time_step_s = static_cast<double>(state.range(0)) / 1000.0;
    DynamicSolver solver(scope, settings);
    BeamLoads loads;
    loads.gravity_mm_per_s2 = Eigen::Vector3d(0.0, -kGravity_mm_per_s2, 0.0);
    NodeSupport handle;
    handle.node = 0;
    const std::vector<NodeSupport> supports{handle};
    long iterations = 0, steps = 0;
    for (auto _ : state) {
        const DynamicStepReport report = solver.step(scope, loads, supports);
        iterations += report.iterations;
        ++steps;
        if (!report.converged) state.SkipWithError("dynamic step did not converge");
    }
    state.counters["newton_iterations_per_step"] =
        static_cast<double>(iterations) / static_cast<double>(steps);
    state.counters["dof"] = static_cast<double>(scope.dof_count());
}
BENCHMARK(BM_DynamicStep)->Arg(5)->Arg(33)->Unit(benchmark::kMicrosecond);

// One Newton iteration of a static solve: assemble internal force and tangent, apply the
// clamp, factorise and solve the block-tridiagonal system, update the configuration.
// Argument: number of elements (the cost must grow linearly with it).
void BM_StaticNewtonIteration(benchmark::State& state) {
    ScopeBeam scope = make_scope(static_cast<std::size_t>(state.range(0)));
    BeamLoads loads;
    loads.gravity_mm_per_s2 = Eigen::Vector3d(0.0, -kGravity_mm_per_s2, 0.0);
    const Eigen::VectorXd f_ext = 1e-3 * loads.assemble(scope);
    NodeSupport clamp;
    clamp.node = 0;
    const SupportStart start = record_support_start(scope, {clamp});
    ScopeBeam::Assembly assembly;
    for (auto _ : state) {
        scope.assemble(assembly, true);
        const SupportMotion motion = support_motion(scope, {clamp}, start, 1.0);
        Eigen::VectorXd increment;
        if (!solve_constrained(assembly.tangent, f_ext - assembly.internal_force, motion,
                               increment))
            state.SkipWithError("singular");
        scope.apply_increment(increment);
        benchmark::DoNotOptimize(increment.data());
    }
}
BENCHMARK(BM_StaticNewtonIteration)
    ->Arg(85)
    ->Arg(170)
    ->Arg(340)
    ->Arg(680)
    ->Unit(benchmark::kMicrosecond);

// The element kernel alone: co-rotational internal force + consistent tangent of one element.
void BM_CorotationalElement(benchmark::State& state) {
    const ScopeBeam scope = make_scope();
    const CorotationalReference& ref = scope.element_reference(0);
    const Eigen::Vector3d xb = scope.position(1) + Eigen::Vector3d(0.01, 0.2, -0.1);
    const Eigen::Matrix3d rb =
        Eigen::AngleAxisd(0.05, Eigen::Vector3d(0.3, 0.5, 0.8).normalized()).toRotationMatrix();
    for (auto _ : state) {
        CorotationalResponse r = corotational_response(ref, scope.position(0),
                                                       Eigen::Matrix3d::Identity(), xb, rb, true);
        benchmark::DoNotOptimize(r.internal_force.data());
    }
}
BENCHMARK(BM_CorotationalElement)->Unit(benchmark::kNanosecond);

/// The 170-element scope bent into a twisted arc (radius 300 mm, node rotations a little off
/// the chord frames), so every element has non-trivial deformation: realistic trig branches.
ScopeBeam make_bent_scope() {
    ScopeBeam scope = make_scope();
    const double radius_mm = 300.0;
    for (std::size_t i = 0; i < scope.node_count(); ++i) {
        const double s = scope.arc_length_mm(i);
        const double a = s / radius_mm;
        const Eigen::Vector3d x(radius_mm * std::sin(a), radius_mm * (1.0 - std::cos(a)), 0.02 * s);
        const Eigen::Matrix3d r =
            (Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()) *
             Eigen::AngleAxisd(0.002 * static_cast<double>(i), Eigen::Vector3d::UnitX()))
                .toRotationMatrix();
        scope.set_pose(i, x, r);
    }
    return scope;
}

// One assembly as the world time step does it: internal force, material and full tangent and
// the consistent mass, in one pass over the elements. Argument: number of elements (170).
void BM_AssembleWithMass(benchmark::State& state) {
    const ScopeBeam scope = make_bent_scope();
    ScopeBeam::Assembly assembly;
    BlockTridiagonalMatrix mass;
    for (auto _ : state) {
        scope.assemble(assembly, true, &mass);
        benchmark::DoNotOptimize(assembly.internal_force.data());
        benchmark::DoNotOptimize(&mass.diagonal(0));
    }
}
BENCHMARK(BM_AssembleWithMass)->Arg(170)->Unit(benchmark::kMicrosecond);

// Factorisation of M/h^2 + C/h + K_T (h = 10 ms, thesis Rayleigh damping, handle clamped at
// node 0) and one solve, as in the world time step. Argument: number of elements (170).
void BM_FactorizeSolve(benchmark::State& state) {
    const ScopeBeam scope = make_bent_scope();
    ScopeBeam::Assembly assembly;
    BlockTridiagonalMatrix mass;
    scope.assemble(assembly, true, &mass);
    const double h = 0.010;
    const RayleighDamping damping = RayleighDamping::thesis_cf_q160l();
    BlockTridiagonalMatrix system = assembly.tangent;
    system.add_scaled(mass, 1.0 / (h * h) + damping.mass_coefficient_per_s / h);
    system.add_scaled(assembly.material_tangent, damping.stiffness_coefficient_s / h);
    for (std::size_t dof = 0; dof < 6; ++dof)
        system.constrain_dof(dof);
    Eigen::VectorXd rhs = assembly.internal_force;
    rhs.head<6>().setZero();
    BlockTridiagonalSolver solver;
    for (auto _ : state) {
        if (!solver.factorize(system)) state.SkipWithError("singular");
        Eigen::VectorXd x = solver.solve(rhs);
        benchmark::DoNotOptimize(x.data());
    }
}
BENCHMARK(BM_FactorizeSolve)->Arg(170)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
