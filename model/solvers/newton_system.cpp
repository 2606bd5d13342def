#include "model/solvers/newton_system.hpp"

#include <cmath>
#include <vector>

namespace scopekin::model {

ResidualNorm free_residual_norm(const Eigen::VectorXd& residual, const SupportMotion& motion) {
    Eigen::VectorXd free = residual;
    for (std::size_t dof : motion.dofs)
        free(static_cast<Eigen::Index>(dof)) = 0.0;
    ResidualNorm n;
    double f2 = 0.0, m2 = 0.0;
    for (Eigen::Index i = 0; i < free.size(); ++i)
        ((i % 6) < 3 ? f2 : m2) += free(i) * free(i);
    n.force_N = std::sqrt(f2);
    n.moment_Nmm = std::sqrt(m2);
    return n;
}

bool solve_constrained(BlockTridiagonalMatrix& a, Eigen::VectorXd r, const SupportMotion& motion,
                       Eigen::VectorXd& increment) {
    for (std::size_t k = 0; k < motion.dofs.size(); ++k) {
        const double value = motion.remaining_increment[k];
        if (value != 0.0) r -= a.column(motion.dofs[k]) * value;
    }
    for (std::size_t k = 0; k < motion.dofs.size(); ++k) {
        a.constrain_dof(motion.dofs[k]);
        r(static_cast<Eigen::Index>(motion.dofs[k])) = motion.remaining_increment[k];
    }
    BlockTridiagonalSolver solver;
    if (!solver.factorize(a)) return false;
    increment = solver.solve(r);
    return increment.allFinite();
}

}  // namespace scopekin::model
