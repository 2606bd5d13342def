#include "model/beam/corotational_element.hpp"

#include <array>
#include <cmath>

#include "model/beam/rotation.hpp"

namespace scopekin::model {
namespace {
// Indices of the 7 deformational DOFs inside the 12 local DOFs of Eq. (4.2): node a sits at
// the local origin with no translation, node b moves only along the chord.
constexpr std::array<Eigen::Index, 7> kDeformationalDofs{6, 3, 4, 5, 9, 10, 11};
}  // namespace

CorotationalReference make_corotational_reference(const BeamSection& section, const Eigen::Vector3d& a,
                                                  const Eigen::Vector3d& b) {
  CorotationalReference ref;
  ref.length_mm = (b - a).norm();
  ref.frame = reference_element_frame(a, b);
  const Mat12 k = timoshenko_local_stiffness(section, ref.length_mm);
  for (std::size_t i = 0; i < 7; ++i)
    for (std::size_t j = 0; j < 7; ++j)
      ref.local_stiffness(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          k(kDeformationalDofs[i], kDeformationalDofs[j]);
  ref.local_mass = timoshenko_local_mass(section, ref.length_mm);
  return ref;
}

CorotationalKinematics corotational_kinematics(const CorotationalReference& ref, const Eigen::Vector3d& xa,
                                               const Eigen::Matrix3d& ra, const Eigen::Vector3d& xb,
                                               const Eigen::Matrix3d& rb) {
  CorotationalKinematics k;
  const Eigen::Vector3d chord = xb - xa;
  const double l = chord.norm();
  k.length_mm = l;
  const Eigen::Vector3d r1 = chord / l;
  // Battini & Pacoste Eq. (17)-(19): the frame's twist follows the mean of the nodes' second axes.
  const Eigen::Vector3d qa = ra * ref.frame.col(1);
  const Eigen::Vector3d qb = rb * ref.frame.col(1);
  const Eigen::Vector3d q = 0.5 * (qa + qb);
  Eigen::Vector3d r3 = r1.cross(q);
  r3.normalize();
  const Eigen::Vector3d r2 = r3.cross(r1);
  k.frame.col(0) = r1;
  k.frame.col(1) = r2;
  k.frame.col(2) = r3;

  const Eigen::Matrix3d rbar_a = k.frame.transpose() * ra * ref.frame;
  const Eigen::Matrix3d rbar_b = k.frame.transpose() * rb * ref.frame;
  const Eigen::Vector3d theta_a = rotation_log(rbar_a);
  const Eigen::Vector3d theta_b = rotation_log(rbar_b);
  k.deformation(0) = l - ref.length_mm;
  k.deformation.segment<3>(1) = theta_a;
  k.deformation.segment<3>(4) = theta_b;

  // Spin of the frame, local components w = G^T dq (Battini & Pacoste Eq. 33), written with
  // global vectors: w1 from the mean second axis, w2 and w3 from the chord's rotation.
  const double q1 = q.dot(r1);
  const double q2 = q.dot(r2);  // > 0 by construction of r3
  Eigen::Matrix<double, 3, 12> g = Eigen::Matrix<double, 3, 12>::Zero();
  const Eigen::Vector3d twist_a = qa.cross(r3) / (2.0 * q2);
  const Eigen::Vector3d twist_b = qb.cross(r3) / (2.0 * q2);
  g.block<1, 3>(0, 0) = (q1 / (q2 * l)) * r3.transpose();
  g.block<1, 3>(0, 3) = twist_a.transpose();
  g.block<1, 3>(0, 6) = -(q1 / (q2 * l)) * r3.transpose();
  g.block<1, 3>(0, 9) = twist_b.transpose();
  g.block<1, 3>(1, 0) = r3.transpose() / l;
  g.block<1, 3>(1, 6) = -r3.transpose() / l;
  g.block<1, 3>(2, 0) = -r2.transpose() / l;
  g.block<1, 3>(2, 6) = r2.transpose() / l;

  k.b_matrix.setZero();
  k.b_matrix.block<1, 3>(0, 0) = -r1.transpose();
  k.b_matrix.block<1, 3>(0, 6) = r1.transpose();
  // d theta_i = T^-1(theta_i) (R_r^T dw_i - w)
  Eigen::Matrix<double, 3, 12> spin_a = -g;
  spin_a.block<3, 3>(0, 3) += k.frame.transpose();
  Eigen::Matrix<double, 3, 12> spin_b = -g;
  spin_b.block<3, 3>(0, 9) += k.frame.transpose();
  k.b_matrix.block<3, 12>(1, 0) = left_jacobian_inverse(theta_a) * spin_a;
  k.b_matrix.block<3, 12>(4, 0) = left_jacobian_inverse(theta_b) * spin_b;
  return k;
}

CorotationalResponse corotational_response(const CorotationalReference& ref, const Eigen::Vector3d& xa,
                                           const Eigen::Matrix3d& ra, const Eigen::Vector3d& xb,
                                           const Eigen::Matrix3d& rb, bool with_tangent) {
  CorotationalResponse out;
  out.kinematics = corotational_kinematics(ref, xa, ra, xb, rb);
  out.local_force = ref.local_stiffness * out.kinematics.deformation;
  out.internal_force = out.kinematics.b_matrix.transpose() * out.local_force;
  if (!with_tangent) return out;
  out.material_tangent = out.kinematics.b_matrix.transpose() * ref.local_stiffness * out.kinematics.b_matrix;
  const double step_translation = 1e-7 * ref.length_mm;
  const double step_rotation = 1e-7;
  for (int var = 0; var < 12; ++var) {
    Eigen::Vector3d pxa = xa, pxb = xb;
    Eigen::Matrix3d pra = ra, prb = rb;
    const int node = var / 6;
    const int comp = var % 3;
    const bool is_rotation = (var % 6) >= 3;
    const double step = is_rotation ? step_rotation : step_translation;
    Eigen::Vector3d delta = Eigen::Vector3d::Zero();
    delta(comp) = step;
    if (!is_rotation) {
      (node == 0 ? pxa : pxb) += delta;
    } else if (node == 0) {
      pra = rotation_exp(delta) * ra;
    } else {
      prb = rotation_exp(delta) * rb;
    }
    const CorotationalKinematics pk = corotational_kinematics(ref, pxa, pra, pxb, prb);
    out.geometric_tangent.col(var) =
        (pk.b_matrix.transpose() * out.local_force - out.internal_force) / step;
  }
  return out;
}

}  // namespace scopekin::model
