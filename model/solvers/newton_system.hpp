#pragma once
// One Newton correction shared by the static and the dynamic solver: apply prescribed DOFs to
// a block-tridiagonal system, solve it, and measure the residual on the free DOFs.
#include <Eigen/Dense>

#include "model/beam/beam_loads.hpp"
#include "model/linalg/block_tridiagonal.hpp"

namespace scopekin::model {

/// Residual norms on the free DOFs: forces [N] and moments [N mm] measured separately.
struct ResidualNorm {
    double force_N = 0;
    double moment_Nmm = 0;
};
ResidualNorm free_residual_norm(const Eigen::VectorXd& residual, const SupportMotion& motion);

/// Largest entry of a Newton correction: translations relative to the beam length, spins in rad.
double step_size(const ScopeBeam& beam, const Eigen::VectorXd& increment);

/// Solves A d = r with d fixed to motion.remaining_increment on the supported DOFs.
/// Returns false if the matrix is singular (e.g. an unsupported beam in a static solve).
bool solve_constrained(BlockTridiagonalMatrix& a, Eigen::VectorXd r, const SupportMotion& motion,
                       Eigen::VectorXd& increment);

}  // namespace scopekin::model
