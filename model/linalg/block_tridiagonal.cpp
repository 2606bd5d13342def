#include "model/linalg/block_tridiagonal.hpp"

#include <cmath>

namespace scopekin::model {

BlockTridiagonalMatrix::BlockTridiagonalMatrix(std::size_t block_count) { resize(block_count); }

void BlockTridiagonalMatrix::resize(std::size_t n) {
  diagonal_.assign(n, Mat6::Zero());
  upper_.assign(n > 0 ? n - 1 : 0, Mat6::Zero());
  lower_.assign(n > 0 ? n - 1 : 0, Mat6::Zero());
}

void BlockTridiagonalMatrix::set_zero() {
  for (auto& b : diagonal_) b.setZero();
  for (auto& b : upper_) b.setZero();
  for (auto& b : lower_) b.setZero();
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
  for (std::size_t i = 0; i < diagonal_.size(); ++i) diagonal_[i] += factor * other.diagonal_[i];
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

bool BlockTridiagonalSolver::factorize(const BlockTridiagonalMatrix& a) {
  const std::size_t n = a.block_count();
  pivots_.clear();
  pivots_.reserve(n);
  multipliers_.assign(n > 0 ? n - 1 : 0, Mat6::Zero());
  upper_.assign(n > 0 ? n - 1 : 0, Mat6::Zero());
  Mat6 pivot = n > 0 ? a.diagonal(0) : Mat6::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    pivots_.emplace_back(pivot);
    // A singular 6x6 pivot shows up as a vanishing diagonal entry of its U factor relative to
    // the largest one (a ratio test, so blocks mixing N/mm and N mm/rad scales still pass).
    const Vec6 u_diagonal = pivots_.back().matrixLU().diagonal().cwiseAbs();
    const double largest = u_diagonal.maxCoeff();
    if (!std::isfinite(largest) || !(largest > 0.0) || u_diagonal.minCoeff() <= 1e-14 * largest) return false;
    if (i + 1 < n) {
      upper_[i] = a.upper(i);
      multipliers_[i] = a.lower(i) * pivots_.back().inverse();
      pivot = a.diagonal(i + 1) - multipliers_[i] * a.upper(i);
    }
  }
  return true;
}

Eigen::VectorXd BlockTridiagonalSolver::solve(const Eigen::VectorXd& rhs) const {
  const std::size_t n = pivots_.size();
  Eigen::VectorXd y = rhs;
  for (std::size_t i = 1; i < n; ++i) {
    const auto r = static_cast<Eigen::Index>(6 * i);
    y.segment<6>(r) -= multipliers_[i - 1] * y.segment<6>(r - 6);
  }
  Eigen::VectorXd x(y.size());
  for (std::size_t k = n; k-- > 0;) {
    const auto r = static_cast<Eigen::Index>(6 * k);
    Vec6 v = y.segment<6>(r);
    if (k + 1 < n) v -= upper_[k] * x.segment<6>(r + 6);
    x.segment<6>(r) = pivots_[k].solve(v);
  }
  return x;
}

}  // namespace scopekin::model
