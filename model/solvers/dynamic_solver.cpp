#include "model/solvers/dynamic_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/model_error.hpp"
#include "model/solvers/newton_system.hpp"

namespace scopekin::model {

void DynamicSettings::validate() const {
    validate_time_step_and_damping(time_step_s, damping, "dynamic");
    if (max_iterations < 1) throw ModelError("dynamic.max_iterations: must be >= 1");
    require_positive(relative_tolerance, "dynamic.relative_tolerance");
}

DynamicSolver::DynamicSolver(const ScopeBeam& beam, DynamicSettings settings)
    : settings_(settings) {
    settings_.validate();
    velocity_ = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(beam.dof_count()));
}

DynamicStepReport DynamicSolver::step(ScopeBeam& beam, const BeamLoads& loads,
                                      const std::vector<NodeSupport>& supports) {
    validate_supports(beam, supports);
    const ScopeBeam::Configuration saved = beam.configuration();
    // Fast path: velocity predictor + modified Newton. If it fails (a violent step at large h),
    // start over from q_n with plain Newton (no predictor, fresh tangent every correction).
    DynamicStepReport report = attempt(beam, loads, supports, true);
    if (!report.converged) {
        beam.restore(saved);
        const int fast_iterations = report.iterations;
        report = attempt(beam, loads, supports, false);
        report.iterations += fast_iterations;
    }
    if (!report.converged) {
        beam.restore(saved);  // a failed step leaves the state as it was (velocity untouched)
        return report;
    }
    velocity_ = step_increment_ / settings_.time_step_s;
    time_s_ += settings_.time_step_s;
    return report;
}

DynamicStepReport DynamicSolver::attempt(ScopeBeam& beam, const BeamLoads& loads,
                                         const std::vector<NodeSupport>& supports, bool fast) {
    const double h = settings_.time_step_s;
    const Eigen::VectorXd f_ext = loads.assemble(beam);
    const SupportStart start = record_support_start(beam, supports);

    // Matrices of the step, frozen at its start (q_n).
    beam.assemble(assembly_, true, &mass_);
    damping_ = mass_;
    damping_.set_zero();
    damping_.add_scaled(mass_, settings_.damping.mass_coefficient_per_s);
    damping_.add_scaled(assembly_.material_tangent, settings_.damping.stiffness_coefficient_s);
    const Eigen::VectorXd momentum_term = mass_.multiply(velocity_) / h;  // M v_n / h

    // Predictor: free DOFs keep their velocity (fast path only), supported DOFs jump to their
    // targets. From then on every supported DOF has a zero increment, so one factorisation
    // serves all corrections.
    step_increment_ =
        fast ? Eigen::VectorXd(h * velocity_) : Eigen::VectorXd::Zero(velocity_.size());
    const SupportMotion to_targets = support_motion(beam, supports, start, 1.0);
    for (std::size_t k = 0; k < to_targets.dofs.size(); ++k)
        step_increment_(static_cast<Eigen::Index>(to_targets.dofs[k])) =
            to_targets.remaining_increment[k];
    beam.apply_increment(step_increment_);

    // Newton on M/h^2 + C/h + K_T. Fast path: modified Newton, the factorisation is rebuilt at the
    // current configuration only when the residual stops falling fast (ratio > 0.25).
    BlockTridiagonalSolver factorization;
    auto refactorize = [&](const BlockTridiagonalMatrix& tangent) {
        system_ = tangent;
        loads.add_spring_stiffness(system_);
        system_.add_scaled(mass_, 1.0 / (h * h));
        system_.add_scaled(damping_, 1.0 / h);
        for (std::size_t dof : to_targets.dofs)
            system_.constrain_dof(dof);
        return factorization.factorize(system_);
    };
    DynamicStepReport report;
    bool factorized_here = fast;  // plain Newton builds the tangent at the supported targets first
    if (fast && !refactorize(assembly_.tangent)) return report;
    double last_step = std::numeric_limits<double>::infinity();
    double previous_residual = std::numeric_limits<double>::infinity();
    for (int it = 0; it <= settings_.max_iterations; ++it) {
        beam.assemble(assembly_, false);
        Eigen::VectorXd residual = f_ext - assembly_.internal_force -
                                   (mass_.multiply(step_increment_) / (h * h) - momentum_term +
                                    damping_.multiply(step_increment_) / h);
        loads.add_spring_forces(beam, residual);
        if (!residual.allFinite()) break;
        const SupportMotion motion = support_motion(beam, supports, start, 1.0);
        const ResidualNorm norm = free_residual_norm(residual, motion);
        report.iterations = it;
        report.residual_force_N = norm.force_N;
        double prescribed_left = 0.0;
        for (double v : motion.remaining_increment)
            prescribed_left = std::max(prescribed_left, std::abs(v));
        const double scale = f_ext.norm() + assembly_.internal_force.norm() + 1e-6;
        const double tolerance = settings_.relative_tolerance * scale;
        const bool residual_small =
            norm.force_N <= tolerance &&
            norm.moment_Nmm <= tolerance * beam.arc_length_mm(beam.node_count() - 1);
        if ((residual_small || last_step < 1e-11) && prescribed_left < 1e-9) {
            report.converged = true;
            break;
        }
        if (it == settings_.max_iterations) break;
        const double residual_measure =
            norm.force_N + norm.moment_Nmm / beam.arc_length_mm(beam.node_count() - 1);
        if (fast && it > 2 && residual_measure > previous_residual) break;  // diverging: fall back
        if (!factorized_here || !fast || residual_measure > 0.25 * previous_residual) {
            if (it > 0 || !fast) beam.assemble(assembly_, true);
            if (!refactorize(assembly_.tangent)) break;
            factorized_here = true;
        }
        previous_residual = residual_measure;
        for (std::size_t dof : to_targets.dofs)
            residual(static_cast<Eigen::Index>(dof)) = 0.0;
        const Eigen::VectorXd increment = factorization.solve(residual);
        if (!increment.allFinite()) break;
        beam.apply_increment(increment);
        step_increment_ += increment;
        last_step = step_size(beam, increment);
    }
    return report;
}

}  // namespace scopekin::model
