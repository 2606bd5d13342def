#include "model/solvers/static_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "model/model_error.hpp"
#include "model/solvers/newton_system.hpp"

namespace scopekin::model {
namespace {}  // namespace

double step_size(const ScopeBeam& beam, const Eigen::VectorXd& increment) {
    const double length = beam.arc_length_mm(beam.node_count() - 1);
    double largest = 0.0;
    for (Eigen::Index i = 0; i < increment.size(); ++i)
        largest = std::max(largest, std::abs(increment(i)) / ((i % 6) < 3 ? length : 1.0));
    return largest;
}

std::string StaticReport::convergence_table() const {
    std::ostringstream out;
    out << "  load factor  iterations  residual force [N]  residual moment [N mm]  status\n";
    for (const LoadStepLog& s : steps) {
        out.setf(std::ios::fixed);
        out.precision(4);
        out << "  " << s.load_factor << "       " << s.iterations << "          ";
        out.unsetf(std::ios::fixed);
        out.precision(3);
        out << std::scientific << s.residual_force_N << "           " << s.residual_moment_Nmm
            << "               " << (s.converged ? "converged" : "rejected (step halved)") << "\n";
        out.unsetf(std::ios::scientific);
    }
    return out.str();
}

StaticReport solve_static(ScopeBeam& beam, const BeamLoads& loads,
                          const std::vector<NodeSupport>& supports,
                          const StaticSettings& settings) {
    if (settings.load_steps < 1) throw ModelError("static.load_steps: must be >= 1");
    if (settings.max_iterations < 1) throw ModelError("static.max_iterations: must be >= 1");
    require_positive(settings.relative_tolerance, "static.relative_tolerance");
    validate_supports(beam, supports);
    const Eigen::VectorXd f_full = loads.assemble(beam);
    const SupportStart start = record_support_start(beam, supports);

    StaticReport report;
    ScopeBeam::Assembly assembly;
    double lambda = 0.0;
    double step = 1.0 / settings.load_steps;
    int halvings = 0;
    while (lambda < 1.0 - 1e-12) {
        const double target = std::min(1.0, lambda + step);
        const ScopeBeam::Configuration saved = beam.configuration();
        LoadStepLog log;
        log.load_factor = target;
        const Eigen::VectorXd f_ext = target * f_full;
        double last_step = std::numeric_limits<double>::infinity();
        for (int it = 0; it <= settings.max_iterations; ++it) {
            beam.assemble(assembly, false);  // the tangent only when another correction is needed
            Eigen::VectorXd residual = f_ext - assembly.internal_force;
            loads.add_spring_forces(beam, residual);
            if (!residual.allFinite()) break;
            const SupportMotion motion = support_motion(beam, supports, start, target);
            const ResidualNorm norm = free_residual_norm(residual, motion);
            // Scale: the applied load plus the internal forces it balances (reactions included).
            const double force_scale = f_ext.norm() + assembly.internal_force.norm();
            double prescribed_left = 0.0;
            for (double v : motion.remaining_increment)
                prescribed_left = std::max(prescribed_left, std::abs(v));
            log.iterations = it;
            log.residual_force_N = norm.force_N;
            log.residual_moment_Nmm = norm.moment_Nmm;
            const double tolerance =
                settings.relative_tolerance * force_scale + settings.absolute_force_tolerance_N;
            // Converged when the residual is small, or when Newton's last correction is at round-off
            // level (the residual then sits at its floor, ~1e-16 EA, which can exceed a tolerance
            // relative to a small load).
            const bool residual_small =
                norm.force_N <= tolerance &&
                norm.moment_Nmm <= tolerance * beam.arc_length_mm(beam.node_count() - 1);
            if ((residual_small || last_step < 1e-11) && prescribed_left < 1e-12) {
                log.converged = true;
                break;
            }
            if (it == settings.max_iterations) break;
            beam.assemble(assembly, true);
            loads.add_spring_stiffness(assembly.tangent);
            Eigen::VectorXd increment;
            if (!solve_constrained(assembly.tangent, residual, motion, increment)) {
                report.message = "singular tangent stiffness at load factor " +
                                 std::to_string(target) +
                                 ": is the beam supported against rigid motion?";
                break;
            }
            beam.apply_increment(increment);
            last_step = step_size(beam, increment);
        }
        report.total_iterations += log.iterations;
        report.steps.push_back(log);
        if (log.converged) {
            lambda = target;
            if (halvings > 0 && log.iterations < settings.max_iterations / 3)
                step = std::min(2.0 * step, 1.0 / settings.load_steps);
            continue;
        }
        beam.restore(saved);
        if (!report.message.empty() && report.message.rfind("singular", 0) == 0) return report;
        if (++halvings > settings.max_halvings) {
            report.message = "Newton did not converge at load factor " + std::to_string(target) +
                             " after " + std::to_string(settings.max_halvings) + " step halvings";
            return report;
        }
        step *= 0.5;
    }
    report.converged = true;
    report.message = "converged";
    return report;
}

}  // namespace scopekin::model
