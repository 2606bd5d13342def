#pragma once
// Finite rotations on SO(3) for the co-rotational beam (no Euler angles, so no gimbal
// singularity: node orientations are stored as rotation matrices and updated multiplicatively).
#include <Eigen/Dense>

namespace scopekin::model {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

/// Skew-symmetric matrix S(v) with S(v) w = v x w.
Mat3 skew(const Vec3& v);

/// Rodrigues' formula: exp(S(theta)), theta = rotation vector in rad.
Mat3 rotation_exp(const Vec3& theta_rad);

/// Principal logarithm: rotation vector theta (|theta| <= pi, rad) with exp(S(theta)) = R.
/// Stable near 0 and near pi.
Vec3 rotation_log(const Mat3& rotation);

/// Inverse of the left Jacobian of SO(3): for R = exp(S(theta)) and a spatial (left) spin
/// dw with dR = S(dw) R, the rotation-vector increment is dtheta = T^-1(theta) dw.
/// T^-1 = I - S/2 + (1 - (t/2) cot(t/2)) / t^2 S^2, t = |theta| (Battini & Pacoste 2002, Eq. 13).
Mat3 left_jacobian_inverse(const Vec3& theta_rad);

/// Re-orthonormalise a rotation matrix that has drifted by round-off (polar projection).
Mat3 reorthonormalize(const Mat3& rotation);

}  // namespace scopekin::model
