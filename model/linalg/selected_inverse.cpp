#include "model/linalg/selected_inverse.hpp"

#include <cmath>

#include "model/model_error.hpp"

namespace scopekin::model {
namespace {

/// Same singularity test as the block solver: a vanishing U diagonal relative to the largest.
bool regular(const Eigen::PartialPivLU<Mat6>& lu) {
    const Vec6 u = lu.matrixLU().diagonal().cwiseAbs();
    const double largest = u.maxCoeff();
    return std::isfinite(largest) && largest > 0.0 && u.minCoeff() > 1e-14 * largest;
}

}  // namespace

bool SelectedInverse::translational_blocks(const BlockTridiagonalMatrix& a,
                                           const std::vector<std::size_t>& nodes,
                                           Eigen::MatrixXd& blocks) {
    const std::size_t k = nodes.size();
    blocks.resize(static_cast<Eigen::Index>(3 * k), static_cast<Eigen::Index>(3 * k));
    if (k == 0) return true;
    const std::size_t n = a.block_count();
    for (std::size_t c = 0; c < k; ++c)
        if (nodes[c] >= n || (c > 0 && nodes[c] <= nodes[c - 1]))
            throw ModelError(
                "selected inverse: contact nodes must be strictly increasing and inside the "
                "matrix");
    const std::size_t lo = nodes.front(), hi = nodes.back();
    forward_step_.resize(n);
    backward_step_.resize(n);
    forward_schur_.resize(n);
    backward_schur_.resize(n);

    // Forward sweep 0 .. hi: S_i and P_i.
    Mat6 s = a.diagonal(0);
    for (std::size_t i = 0; i <= hi; ++i) {
        forward_schur_[i] = s;
        if (i == hi) break;
        const Eigen::PartialPivLU<Mat6> lu(s);
        if (!regular(lu)) return false;
        forward_step_[i] = -lu.solve(a.upper(i));
        s = a.diagonal(i + 1) + a.lower(i) * forward_step_[i];
    }
    // Backward sweep n-1 .. lo: T_i and Q_i.
    Mat6 t = a.diagonal(n - 1);
    for (std::size_t i = n - 1;; --i) {
        backward_schur_[i] = t;
        if (i == lo) break;
        const Eigen::PartialPivLU<Mat6> lu(t);
        if (!regular(lu)) return false;
        backward_step_[i] = -lu.solve(a.lower(i - 1));
        t = a.diagonal(i - 1) + a.upper(i - 1) * backward_step_[i];
    }
    // For each contact node j: the translational columns of G_jj, then walk to the other nodes.
    using Mat63 = Eigen::Matrix<double, 6, 3>;
    for (std::size_t b = 0; b < k; ++b) {
        const std::size_t j = nodes[b];
        const Eigen::PartialPivLU<Mat6> lu(forward_schur_[j] + backward_schur_[j] - a.diagonal(j));
        if (!regular(lu)) return false;
        const Mat63 diagonal_columns = lu.solve(Eigen::Matrix<double, 6, 3>::Identity());
        const auto col = static_cast<Eigen::Index>(3 * b);
        blocks.block<3, 3>(col, col) = diagonal_columns.topRows<3>();
        Mat63 x = diagonal_columns;
        std::size_t next = b;  // walk down towards node lo
        for (std::size_t i = j; i-- > lo && next > 0;) {
            x = forward_step_[i] * x;
            if (i == nodes[next - 1]) {
                --next;
                blocks.block<3, 3>(static_cast<Eigen::Index>(3 * next), col) = x.topRows<3>();
            }
        }
        x = diagonal_columns;
        next = b;  // walk up towards node hi
        for (std::size_t i = j + 1; i <= hi && next + 1 < k; ++i) {
            x = backward_step_[i] * x;
            if (i == nodes[next + 1]) {
                ++next;
                blocks.block<3, 3>(static_cast<Eigen::Index>(3 * next), col) = x.topRows<3>();
            }
        }
    }
    return blocks.allFinite();
}

}  // namespace scopekin::model
