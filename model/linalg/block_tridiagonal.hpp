#pragma once
// Block-tridiagonal linear systems with 6x6 blocks: the matrices of a chain of beam elements
// (node i couples only to nodes i-1 and i+1), i.e. banded with half-bandwidth 11.
// Block LU without inter-block pivoting (Thomas algorithm) and partial pivoting inside each
// 6x6 pivot block: cost O(n) in the number of nodes, storage O(n).
// Fit for the matrices solved here (K_T, M/h^2 + C/h + K_T): block diagonally dominant or
// close to symmetric positive definite once supports are applied.
#include <Eigen/Dense>
#include <vector>

namespace scopekin::model {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

class BlockTridiagonalMatrix {
public:
    explicit BlockTridiagonalMatrix(std::size_t block_count = 0);
    void resize(std::size_t block_count);
    void set_zero();
    std::size_t block_count() const { return diagonal_.size(); }
    std::size_t size() const { return 6 * diagonal_.size(); }

    Mat6& diagonal(std::size_t i) { return diagonal_[i]; }
    const Mat6& diagonal(std::size_t i) const { return diagonal_[i]; }
    /// Block (i, i+1).
    Mat6& upper(std::size_t i) { return upper_[i]; }
    const Mat6& upper(std::size_t i) const { return upper_[i]; }
    /// Block (i+1, i).
    Mat6& lower(std::size_t i) { return lower_[i]; }
    const Mat6& lower(std::size_t i) const { return lower_[i]; }

    /// Adds a 12x12 element matrix coupling nodes i and i+1.
    void add_element(std::size_t first_node, const Eigen::Matrix<double, 12, 12>& element);
    /// y = A x
    Eigen::VectorXd multiply(const Eigen::VectorXd& x) const;
    /// this += factor * other (same block count).
    void add_scaled(const BlockTridiagonalMatrix& other, double factor);
    /// Replaces row and column of DOF `dof` by the identity (for a prescribed DOF whose
    /// increment is moved to the right-hand side beforehand).
    void constrain_dof(std::size_t dof);
    /// Column `dof` (only the non-zero range is filled), used to move prescribed values to the RHS.
    Eigen::VectorXd column(std::size_t dof) const;
    Eigen::MatrixXd to_dense() const;

private:
    std::vector<Mat6> diagonal_, upper_, lower_;
};

/// Factorises a copy and solves; returns false if a pivot block is singular or the result
/// is not finite (for example a beam with no support in a static solve).
/// Block Thomas algorithm: D'_0 = D_0, W_i = D'_i^-1 U_i, D'_{i+1} = D_{i+1} - L_i W_i. Each pivot
/// block is inverted once (Gauss-Jordan with partial pivoting, which also yields W_i), so the
/// solves are plain 6x6 matrix-vector products. Storage is reused between factorisations.
class BlockTridiagonalSolver {
public:
    bool factorize(const BlockTridiagonalMatrix& a);
    Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const;
    /// Solves in place: `x` holds the right-hand side on entry and the solution on return.
    void solve_in_place(Eigen::VectorXd& x) const;

private:
    std::size_t blocks_ = 0;
    std::vector<Mat6> inverse_pivots_;  // D'_i^-1
    std::vector<Mat6> reduced_upper_;   // W_i = D'_i^-1 U_i
    std::vector<Mat6> lower_;           // L_i = A(i+1, i)
};

}  // namespace scopekin::model
