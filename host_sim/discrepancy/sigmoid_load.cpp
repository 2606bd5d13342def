#include "host_sim/discrepancy/sigmoid_load.hpp"

#include <algorithm>

namespace scopekin::discrepancy {

SigmoidLoad load_along_direction(const Eigen::MatrixXd& J, const Eigen::VectorXd& r0,
                                 const Eigen::VectorXd& row_weight, double amplitude_lo,
                                 double amplitude_hi) {
    SigmoidLoad out;
    if (J.cols() != 6 || J.rows() != r0.size() || row_weight.size() != r0.size()) return out;
    const Eigen::MatrixXd Jw = row_weight.asDiagonal() * J;
    const Eigen::VectorXd r0w = r0.cwiseProduct(row_weight);
    Eigen::MatrixXd A = Jw.transpose() * Jw;
    for (Eigen::Index k = 0; k < 6; ++k)
        A(k, k) += 1e-9 + 1e-6 * A(k, k);  // a column no row sees stays at zero
    const Eigen::VectorXd w = A.ldlt().solve(-Jw.transpose() * r0w);
    Eigen::Matrix<double, 3, 2> M;
    for (int axis = 0; axis < 3; ++axis) {
        M(axis, 0) = w[2 * axis];
        M(axis, 1) = w[2 * axis + 1];
    }
    Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
    if (!(svd.singularValues()[0] > 0.0)) return out;
    out.direction = svd.matrixU().col(0);
    Eigen::Index k = 0;
    out.direction.cwiseAbs().maxCoeff(&k);
    const double sign = out.direction[k] < 0.0 ? -1.0 : 1.0;
    out.direction *= sign;
    out.a = sign * svd.singularValues()[0] * svd.matrixV()(0, 0);
    out.b = sign * svd.singularValues()[0] * svd.matrixV()(1, 0);
    out.jacobian_along_direction = Eigen::MatrixXd::Zero(r0.size(), 4);
    for (int axis = 0; axis < 3; ++axis) {
        out.jacobian_along_direction.col(0) += out.direction[axis] * J.col(2 * axis);
        out.jacobian_along_direction.col(1) += out.direction[axis] * J.col(2 * axis + 1);
    }
    out.a = std::clamp(out.a, amplitude_lo, amplitude_hi);
    out.b = std::clamp(out.b, amplitude_lo, amplitude_hi);
    out.predicted_cost = (r0 + out.a * out.jacobian_along_direction.col(0) +
                          out.b * out.jacobian_along_direction.col(1))
                             .cwiseProduct(row_weight)
                             .squaredNorm();
    out.ok = true;
    return out;
}

}  // namespace scopekin::discrepancy
