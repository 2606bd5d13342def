#include "model/linalg/block_tridiagonal.hpp"

#include <cmath>

namespace scopekin::model {

BlockTridiagonalMatrix::BlockTridiagonalMatrix(std::size_t block_count) {
    resize(block_count);
}

void BlockTridiagonalMatrix::resize(std::size_t n) {
    diagonal_.assign(n, Mat6::Zero());
    upper_.assign(n > 0 ? n - 1 : 0, Mat6::Zero());
    lower_.assign(n > 0 ? n - 1 : 0, Mat6::Zero());
}

void BlockTridiagonalMatrix::set_zero() {
    for (auto& b : diagonal_)
        b.setZero();
    for (auto& b : upper_)
        b.setZero();
    for (auto& b : lower_)
        b.setZero();
}

void BlockTridiagonalMatrix::add_element(std::size_t i, const Eigen::Matrix<double, 12, 12>& e) {
    diagonal_[i] += e.block<6, 6>(0, 0);
    upper_[i] += e.block<6, 6>(0, 6);
    lower_[i] += e.block<6, 6>(6, 0);
    diagonal_[i + 1] += e.block<6, 6>(6, 6);
}

Eigen::VectorXd BlockTridiagonalMatrix::multiply(const Eigen::VectorXd& x) const {
    const std::size_t n = diagonal_.size();
    Eigen::VectorXd y = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * n));
    for (std::size_t i = 0; i < n; ++i) {
        const auto r = static_cast<Eigen::Index>(6 * i);
        y.segment<6>(r) += diagonal_[i] * x.segment<6>(r);
        if (i + 1 < n) {
            y.segment<6>(r) += upper_[i] * x.segment<6>(r + 6);
            y.segment<6>(r + 6) += lower_[i] * x.segment<6>(r);
        }
    }
    return y;
}

void BlockTridiagonalMatrix::add_scaled(const BlockTridiagonalMatrix& other, double factor) {
    for (std::size_t i = 0; i < diagonal_.size(); ++i)
        diagonal_[i] += factor * other.diagonal_[i];
    for (std::size_t i = 0; i < upper_.size(); ++i) {
        upper_[i] += factor * other.upper_[i];
        lower_[i] += factor * other.lower_[i];
    }
}

void BlockTridiagonalMatrix::constrain_dof(std::size_t dof) {
    const std::size_t i = dof / 6;
    const auto c = static_cast<Eigen::Index>(dof % 6);
    diagonal_[i].row(c).setZero();
    diagonal_[i].col(c).setZero();
    diagonal_[i](c, c) = 1.0;
    if (i + 1 < diagonal_.size()) {
        upper_[i].row(c).setZero();
        lower_[i].col(c).setZero();
    }
    if (i > 0) {
        lower_[i - 1].row(c).setZero();
        upper_[i - 1].col(c).setZero();
    }
}

Eigen::VectorXd BlockTridiagonalMatrix::column(std::size_t dof) const {
    const std::size_t n = diagonal_.size();
    Eigen::VectorXd col = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * n));
    const std::size_t i = dof / 6;
    const auto c = static_cast<Eigen::Index>(dof % 6);
    const auto r = static_cast<Eigen::Index>(6 * i);
    col.segment<6>(r) = diagonal_[i].col(c);
    if (i > 0) col.segment<6>(r - 6) = upper_[i - 1].col(c);
    if (i + 1 < n) col.segment<6>(r + 6) = lower_[i].col(c);
    return col;
}

Eigen::MatrixXd BlockTridiagonalMatrix::to_dense() const {
    const auto n = static_cast<Eigen::Index>(size());
    Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
    for (std::size_t i = 0; i < diagonal_.size(); ++i) {
        const auto r = static_cast<Eigen::Index>(6 * i);
        d.block<6, 6>(r, r) = diagonal_[i];
        if (i + 1 < diagonal_.size()) {
            d.block<6, 6>(r, r + 6) = upper_[i];
            d.block<6, 6>(r + 6, r) = lower_[i];
        }
    }
    return d;
}

namespace {
using Augmented = Eigen::Matrix<double, 6, 18, Eigen::RowMajor>;  // [D' | U | I], rows contiguous

/// Gauss-Jordan elimination with partial pivoting on [D' | U | I] -> [I | D'^-1 U | D'^-1]. The
/// pivots are those of an LU with partial pivoting, i.e. the diagonal of U; returns whether they
/// pass the singularity test: a vanishing pivot relative to the largest one (a ratio test, so
/// blocks mixing N/mm and N mm/rad scales still pass).
bool gauss_jordan(Augmented& w) {
    Vec6 pivots;
    for (Eigen::Index k = 0; k < 6; ++k) {
        Eigen::Index p = k;
        for (Eigen::Index r = k + 1; r < 6; ++r)
            if (std::abs(w(r, k)) > std::abs(w(p, k))) p = r;
        if (p != k) w.row(k).swap(w.row(p));
        const double pivot = w(k, k);
        pivots(k) = std::abs(pivot);
        w.row(k) *= 1.0 / pivot;
        for (Eigen::Index r = 0; r < 6; ++r)
            if (r != k) w.row(r) -= w(r, k) * w.row(k);
    }
    const double largest = pivots.maxCoeff();
    return std::isfinite(largest) && largest > 0.0 && pivots.minCoeff() > 1e-14 * largest;
}
}  // namespace

bool BlockTridiagonalSolver::factorize(const BlockTridiagonalMatrix& a) {
    const std::size_t n = a.block_count();
    blocks_ = 0;
    inverse_pivots_.resize(n);
    reduced_upper_.resize(n > 0 ? n - 1 : 0);
    lower_.resize(n > 0 ? n - 1 : 0);
    Augmented w;
    w.leftCols<6>() = n > 0 ? a.diagonal(0) : Mat6::Zero();
    for (std::size_t i = 0; i < n; ++i) {
        const bool last = i + 1 == n;
        if (last)
            w.middleCols<6>(6).setZero();
        else
            w.middleCols<6>(6) = a.upper(i);
        w.rightCols<6>().setIdentity();
        if (!gauss_jordan(w)) return false;
        inverse_pivots_[i] = w.rightCols<6>();
        if (!last) {
            reduced_upper_[i] = w.middleCols<6>(6);
            lower_[i] = a.lower(i);
            w.leftCols<6>() = a.diagonal(i + 1);
            w.leftCols<6>().noalias() -= lower_[i].lazyProduct(reduced_upper_[i]);
        }
    }
    blocks_ = n;
    return true;
}

Eigen::VectorXd BlockTridiagonalSolver::solve(const Eigen::VectorXd& rhs) const {
    Eigen::VectorXd x = rhs;
    solve_in_place(x);
    return x;
}

void BlockTridiagonalSolver::solve_in_place(Eigen::VectorXd& x) const {
    const std::size_t n = blocks_;
    // Forward: g_i = D'_i^-1 (b_i - L_{i-1} g_{i-1}); backward: x_i = g_i - W_i x_{i+1}.
    Vec6 v;
    for (std::size_t i = 0; i < n; ++i) {
        const auto r = static_cast<Eigen::Index>(6 * i);
        v = x.segment<6>(r);
        if (i > 0) v.noalias() -= lower_[i - 1] * x.segment<6>(r - 6);
        x.segment<6>(r).noalias() = inverse_pivots_[i] * v;
    }
    for (std::size_t k = n - (n > 0 ? 1 : 0); k-- > 0;) {
        const auto r = static_cast<Eigen::Index>(6 * k);
        x.segment<6>(r).noalias() -= reduced_upper_[k] * x.segment<6>(r + 6);
    }
}

}  // namespace scopekin::model
