#include "model/beam/rotation.hpp"

#include <algorithm>
#include <cmath>

namespace scopekin::model {

Mat3 skew(const Vec3& v) {
    Mat3 s;
    s << 0.0, -v.z(), v.y(),  //
        v.z(), 0.0, -v.x(),   //
        -v.y(), v.x(), 0.0;
    return s;
}

Mat3 rotation_exp(const Vec3& theta_rad) {
    const double t = theta_rad.norm();
    const Mat3 s = skew(theta_rad);
    if (t < 1e-8) {  // second-order Taylor series; error O(t^3) ~ 1e-24
        return Mat3::Identity() + s + 0.5 * s * s;
    }
    return Mat3::Identity() + (std::sin(t) / t) * s + ((1.0 - std::cos(t)) / (t * t)) * s * s;
}

Vec3 rotation_log(const Mat3& r) {
    const double cos_t = std::clamp(0.5 * (r.trace() - 1.0), -1.0, 1.0);
    const Vec3 axial(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));  // = 2 sin(t) n
    const double sin_t = 0.5 * axial.norm();
    const double t = std::atan2(sin_t, cos_t);
    if (t < 1e-6) {
        return 0.5 * (1.0 + t * t / 6.0) * axial;  // t / (2 sin t) ~ (1 + t^2/6) / 2
    }
    if (t < M_PI - 1e-3) {
        return (t / (2.0 * sin_t)) * axial;
    }
    // Near pi the axial vector vanishes: take the axis from the symmetric part,
    // R + I = 2 n n^T + O(pi - t), using the column with the largest diagonal.
    const Mat3 b = (0.5 * (r + r.transpose()) - cos_t * Mat3::Identity()) / (1.0 - cos_t);
    Eigen::Index k = 0;
    b.diagonal().maxCoeff(&k);
    Vec3 n = b.col(k);
    n.normalize();
    if (n.dot(axial) < 0.0) n = -n;  // keep the sign consistent with sin(t) n
    return t * n;
}

Mat3 left_jacobian_inverse(const Vec3& theta_rad) {
    const double t = theta_rad.norm();
    const Mat3 s = skew(theta_rad);
    double eta = 0.0;
    if (t < 1e-4) {
        eta = 1.0 / 12.0 + t * t / 720.0;  // series of (1 - (t/2)cot(t/2)) / t^2
    } else {
        eta = (1.0 - 0.5 * t / std::tan(0.5 * t)) / (t * t);
    }
    return Mat3::Identity() - 0.5 * s + eta * s * s;
}

Mat3 reorthonormalize(const Mat3& rotation) {
    Eigen::JacobiSVD<Mat3> svd(rotation, Eigen::ComputeFullU | Eigen::ComputeFullV);
    return svd.matrixU() * svd.matrixV().transpose();
}

}  // namespace scopekin::model
