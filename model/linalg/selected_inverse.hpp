#pragma once
// Selected blocks of the inverse of a block-tridiagonal matrix: the translational 3x3 blocks
// G_ab = [A^-1](node_a, node_b) for a few nodes (the contact nodes). With A = M/h^2 + C/h + K_T,
// the scope's implicit step matrix, these blocks are the scope's part of the Delassus operator
// W = H A^-1 H^T (thesis Eq. 4.20, 4.24), without forming A^-1.
//
// Method (Meurant 1992, SIAM J. Matrix Anal. Appl. 13:707, Sec. 4): forward Schur complements
// S_0 = D_0, S_i = D_i - L_{i-1} S_{i-1}^-1 U_{i-1} and backward ones T_{n-1} = D_{n-1},
// T_i = D_i - U_i T_{i+1}^-1 L_i (D diagonal, U upper, L lower blocks). Then
//   G_ii = (S_i + T_i - D_i)^-1,
//   G_ij = P_i G_{i+1,j}  (i < j),  P_i = -S_i^-1 U_i,
//   G_ij = Q_i G_{i-1,j}  (i > j),  Q_i = -T_i^-1 L_{i-1}.
// Walking from each contact node to the others costs one 6x6 by 6x3 product per node passed:
// O(k n) for k contacts on n nodes, against O(k n) full solves of 3 right-hand sides each.
// A need not be symmetric (the co-rotational tangent is not, away from equilibrium).
#include <Eigen/Dense>
#include <vector>

#include "model/linalg/block_tridiagonal.hpp"

namespace scopekin::model {

class SelectedInverse {
public:
    /// Fills `blocks` (3k x 3k, k = nodes.size()) with the translational blocks of A^-1 between
    /// the given nodes, which must be strictly increasing and < A's block count. Returns false if
    /// a Schur complement is singular (A not invertible, e.g. an unsupported beam).
    bool translational_blocks(const BlockTridiagonalMatrix& a,
                              const std::vector<std::size_t>& nodes, Eigen::MatrixXd& blocks);

private:
    std::vector<Mat6> forward_step_;    // P_i
    std::vector<Mat6> backward_step_;   // Q_i
    std::vector<Mat6> forward_schur_;   // S_i
    std::vector<Mat6> backward_schur_;  // T_i
};

}  // namespace scopekin::model
