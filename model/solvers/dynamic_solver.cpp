#include "model/solvers/dynamic_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/model_error.hpp"
#include "model/solvers/newton_system.hpp"

namespace scopekin::model {

void DynamicSettings::validate() const {
  require_positive(time_step_s, "dynamic.time_step_s");
  if (time_step_s < 0.001 - 1e-12 || time_step_s > 0.033 + 1e-12)
    throw ModelError("dynamic.time_step_s: " + std::to_string(time_step_s) + " s is outside [0.001, 0.033] s");
  require_non_negative(damping.mass_coefficient_per_s, "dynamic.damping.mass_coefficient_per_s");
  require_non_negative(damping.stiffness_coefficient_s, "dynamic.damping.stiffness_coefficient_s");
  if (max_iterations < 1) throw ModelError("dynamic.max_iterations: must be >= 1");
  require_positive(relative_tolerance, "dynamic.relative_tolerance");
}

DynamicSolver::DynamicSolver(const ScopeBeam& beam, DynamicSettings settings) : settings_(settings) {
  settings_.validate();
  velocity_ = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(beam.dof_count()));
}

DynamicStepReport DynamicSolver::step(ScopeBeam& beam, const BeamLoads& loads,
                                      const std::vector<NodeSupport>& supports) {
  validate_supports(beam, supports);
  const double h = settings_.time_step_s;
  const Eigen::VectorXd f_ext = loads.assemble(beam);
  const SupportStart start = record_support_start(beam, supports);

  // Matrices of the step, frozen at its start.
  beam.assemble(assembly_, true);
  beam.assemble_mass(mass_);
  damping_ = mass_;
  damping_.set_zero();
  damping_.add_scaled(mass_, settings_.damping.mass_coefficient_per_s);
  damping_.add_scaled(assembly_.material_tangent, settings_.damping.stiffness_coefficient_s);
  const Eigen::VectorXd momentum_term = mass_.multiply(velocity_) / h;  // M v_n / h

  Eigen::VectorXd step_increment = Eigen::VectorXd::Zero(velocity_.size());
  DynamicStepReport report;
  double last_step = std::numeric_limits<double>::infinity();
  for (int it = 0; it <= settings_.max_iterations; ++it) {
    if (it > 0) beam.assemble(assembly_, true);
    const Eigen::VectorXd inertia_damping =
        mass_.multiply(step_increment) / (h * h) - momentum_term + damping_.multiply(step_increment) / h;
    const Eigen::VectorXd residual = f_ext - assembly_.internal_force - inertia_damping;
    if (!residual.allFinite()) break;
    const SupportMotion motion = support_motion(beam, supports, start, 1.0);
    const ResidualNorm norm = free_residual_norm(residual, motion);
    report.iterations = it;
    report.residual_force_N = norm.force_N;
    double prescribed_left = 0.0;
    for (double v : motion.remaining_increment) prescribed_left = std::max(prescribed_left, std::abs(v));
    const double scale = f_ext.norm() + assembly_.internal_force.norm() + 1e-6;
    const double tolerance = settings_.relative_tolerance * scale;
    const bool residual_small =
        norm.force_N <= tolerance && norm.moment_Nmm <= tolerance * beam.arc_length_mm(beam.node_count() - 1);
    if ((residual_small || last_step < 1e-11) && prescribed_left < 1e-12) {
      report.converged = true;
      break;
    }
    if (it == settings_.max_iterations) break;
    system_ = assembly_.tangent;
    system_.add_scaled(mass_, 1.0 / (h * h));
    system_.add_scaled(damping_, 1.0 / h);
    Eigen::VectorXd increment;
    if (!solve_constrained(system_, residual, motion, increment)) break;
    beam.apply_increment(increment);
    step_increment += increment;
    last_step = step_size(beam, increment);
  }
  velocity_ = step_increment / h;
  time_s_ += h;
  return report;
}

}  // namespace scopekin::model
