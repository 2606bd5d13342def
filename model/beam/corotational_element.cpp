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

namespace {

/// The co-rotating frame of an element and the matrix g (3x12) giving its spin in local
/// components, w = g dq (Battini & Pacoste Eq. 33), written with global vectors:
/// w1 from the mean second axis q, w2 and w3 from the chord's rotation.
struct ElementFrame {
  Eigen::Matrix3d frame;
  double length_mm = 0;
  Eigen::Matrix<double, 3, 12> spin;
};

ElementFrame element_frame(const CorotationalReference& ref, const Eigen::Vector3d& xa, const Eigen::Matrix3d& ra,
                           const Eigen::Vector3d& xb, const Eigen::Matrix3d& rb) {
  ElementFrame f;
  const Eigen::Vector3d chord = xb - xa;
  const double l = chord.norm();
  f.length_mm = l;
  const Eigen::Vector3d r1 = chord / l;
  // Battini & Pacoste Eq. (17)-(19): the frame's twist follows the mean of the nodes' second axes.
  const Eigen::Vector3d qa = ra * ref.frame.col(1);
  const Eigen::Vector3d qb = rb * ref.frame.col(1);
  const Eigen::Vector3d q = 0.5 * (qa + qb);
  Eigen::Vector3d r3 = r1.cross(q);
  r3.normalize();
  const Eigen::Vector3d r2 = r3.cross(r1);
  f.frame.col(0) = r1;
  f.frame.col(1) = r2;
  f.frame.col(2) = r3;
  const double q1 = q.dot(r1);
  const double q2 = q.dot(r2);  // > 0 by construction of r3
  f.spin.setZero();
  f.spin.block<1, 3>(0, 0) = (q1 / (q2 * l)) * r3.transpose();
  f.spin.block<1, 3>(0, 3) = (qa.cross(r3) / (2.0 * q2)).transpose();
  f.spin.block<1, 3>(0, 6) = -(q1 / (q2 * l)) * r3.transpose();
  f.spin.block<1, 3>(0, 9) = (qb.cross(r3) / (2.0 * q2)).transpose();
  f.spin.block<1, 3>(1, 0) = r3.transpose() / l;
  f.spin.block<1, 3>(1, 6) = -r3.transpose() / l;
  f.spin.block<1, 3>(2, 0) = -r2.transpose() / l;
  f.spin.block<1, 3>(2, 6) = r2.transpose() / l;
  return f;
}

/// d(T^-T(theta) v) / d(theta) for fixed v (Battini & Pacoste 2002, Eq. 56 without the trailing
/// T^-1, which B already carries): eta (theta v^T - 2 v theta^T + (theta.v) I)
/// + mu S(theta)^2 v theta^T - S(v)/2, eta = (1 - (t/2)cot(t/2))/t^2, mu = eta'(t)/t.
Eigen::Matrix3d moment_transform_derivative(const Eigen::Vector3d& theta, const Eigen::Vector3d& v) {
  const double t = theta.norm();
  double eta = 0.0, mu = 0.0;
  if (t < 1e-3) {
    eta = 1.0 / 12.0 + t * t / 720.0;
    mu = 1.0 / 360.0 + t * t / 7560.0;
  } else {
    const double half_sin = std::sin(0.5 * t);
    eta = (1.0 - 0.5 * t / std::tan(0.5 * t)) / (t * t);
    mu = (t * t + 4.0 * std::cos(t) + t * std::sin(t) - 4.0) / (4.0 * t * t * t * t * half_sin * half_sin);
  }
  const Eigen::Matrix3d s = skew(theta);
  return eta * (theta * v.transpose() - 2.0 * v * theta.transpose() + theta.dot(v) * Eigen::Matrix3d::Identity()) +
         mu * (s * s * v) * theta.transpose() - 0.5 * skew(v);
}

}  // namespace

CorotationalKinematics corotational_kinematics(const CorotationalReference& ref, const Eigen::Vector3d& xa,
                                               const Eigen::Matrix3d& ra, const Eigen::Vector3d& xb,
                                               const Eigen::Matrix3d& rb) {
  const ElementFrame f = element_frame(ref, xa, ra, xb, rb);
  CorotationalKinematics k;
  k.frame = f.frame;
  k.length_mm = f.length_mm;
  const Eigen::Matrix3d rbar_a = k.frame.transpose() * ra * ref.frame;
  const Eigen::Matrix3d rbar_b = k.frame.transpose() * rb * ref.frame;
  const Eigen::Vector3d theta_a = rotation_log(rbar_a);
  const Eigen::Vector3d theta_b = rotation_log(rbar_b);
  k.deformation(0) = f.length_mm - ref.length_mm;
  k.deformation.segment<3>(1) = theta_a;
  k.deformation.segment<3>(4) = theta_b;

  k.b_matrix.setZero();
  k.b_matrix.block<1, 3>(0, 0) = -k.frame.col(0).transpose();
  k.b_matrix.block<1, 3>(0, 6) = k.frame.col(0).transpose();
  // d theta_i = T^-1(theta_i) (R_r^T dw_i - w)
  Eigen::Matrix<double, 3, 12> spin_a = -f.spin;
  spin_a.block<3, 3>(0, 3) += k.frame.transpose();
  Eigen::Matrix<double, 3, 12> spin_b = -f.spin;
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
  const CorotationalKinematics& k = out.kinematics;
  // lazyProduct: coefficient-based products; Eigen's GEMM path is slower at these small sizes.
  const Eigen::Matrix<double, 7, 12> kb = ref.local_stiffness.lazyProduct(k.b_matrix);
  out.material_tangent = k.b_matrix.transpose().lazyProduct(kb);

  // Geometric tangent: the variation of B^T f_l with f_l frozen. With m_i = T^-T(theta_i) f_theta_i
  // and spin_i = [.. R_r^T at node i ..] - g, f_g = N r^T + sum_i spin_i^T m_i, so
  //   K_geo = N D + sum_i [ -S(R_r m_i) R_r g (rows of node i's spin) + spin_i^T H_i B_theta_i ]
  //           - d(g^T (m_a + m_b))/dq,
  // D = d r / dq (chord direction), H_i = d(T^-T v)/d(theta) (Battini & Pacoste 2002, Sec. 5).
  const ElementFrame f = element_frame(ref, xa, ra, xb, rb);
  const double axial_force = out.local_force(0);
  const Eigen::Vector3d theta_a = k.deformation.segment<3>(1);
  const Eigen::Vector3d theta_b = k.deformation.segment<3>(4);
  const Eigen::Vector3d m_a = left_jacobian_inverse(theta_a).transpose() * out.local_force.segment<3>(1);
  const Eigen::Vector3d m_b = left_jacobian_inverse(theta_b).transpose() * out.local_force.segment<3>(4);
  Mat12& kg = out.geometric_tangent;
  kg.setZero();
  const Eigen::Vector3d r1 = f.frame.col(0);
  const Eigen::Matrix3d d3 = axial_force * (Eigen::Matrix3d::Identity() - r1 * r1.transpose()) / f.length_mm;
  kg.block<3, 3>(0, 0) += d3;
  kg.block<3, 3>(0, 6) -= d3;
  kg.block<3, 3>(6, 0) -= d3;
  kg.block<3, 3>(6, 6) += d3;
  const Eigen::Matrix<double, 3, 12> frame_spin_global = f.frame * f.spin;
  kg.block<3, 12>(3, 0) -= skew(f.frame * m_a) * frame_spin_global;
  kg.block<3, 12>(9, 0) -= skew(f.frame * m_b) * frame_spin_global;
  Eigen::Matrix<double, 3, 12> spin_a = -f.spin;
  spin_a.block<3, 3>(0, 3) += f.frame.transpose();
  Eigen::Matrix<double, 3, 12> spin_b = -f.spin;
  spin_b.block<3, 3>(0, 9) += f.frame.transpose();
  const Eigen::Matrix<double, 3, 12> hb_a =
      moment_transform_derivative(theta_a, out.local_force.segment<3>(1)).lazyProduct(k.b_matrix.block<3, 12>(1, 0));
  const Eigen::Matrix<double, 3, 12> hb_b =
      moment_transform_derivative(theta_b, out.local_force.segment<3>(4)).lazyProduct(k.b_matrix.block<3, 12>(4, 0));
  kg += spin_a.transpose().lazyProduct(hb_a);
  kg += spin_b.transpose().lazyProduct(hb_b);
  // d(g^T m)/dq with m = m_a + m_b frozen. g^T m = [t; w_a; -t; w_b] with
  //   t = m1 q1/(q2 l) r3 + (m2 r3 - m3 r2)/l,   w_i = m1/(2 q2) (q_i x r3),
  // and every ingredient varies linearly: d r_j = -S(r_j) Omega dq (Omega = R_r g, the frame's
  // global spin), d q_i = -S(q_i) dw_i, d l = r1 . (dx_b - dx_a).
  const Eigen::Vector3d m = m_a + m_b;
  const Eigen::Vector3d r2 = f.frame.col(1), r3 = f.frame.col(2);
  const Eigen::Vector3d qa = ra * ref.frame.col(1), qb = rb * ref.frame.col(1);
  const Eigen::Vector3d q = 0.5 * (qa + qb);
  const double l = f.length_mm, q1 = q.dot(r1), q2 = q.dot(r2);
  using Mat3x12 = Eigen::Matrix<double, 3, 12>;
  using Row12 = Eigen::Matrix<double, 1, 12>;
  const Mat3x12 d_r1 = -skew(r1) * frame_spin_global;
  const Mat3x12 d_r2 = -skew(r2) * frame_spin_global;
  const Mat3x12 d_r3 = -skew(r3) * frame_spin_global;
  Mat3x12 d_qa = Mat3x12::Zero(), d_qb = Mat3x12::Zero();
  d_qa.block<3, 3>(0, 3) = -skew(qa);
  d_qb.block<3, 3>(0, 9) = -skew(qb);
  const Mat3x12 d_q = 0.5 * (d_qa + d_qb);
  Row12 d_l = Row12::Zero();
  d_l.segment<3>(0) = -r1.transpose();
  d_l.segment<3>(6) = r1.transpose();
  const Row12 d_q1 = r1.transpose() * d_q + q.transpose() * d_r1;
  const Row12 d_q2 = r2.transpose() * d_q + q.transpose() * d_r2;
  const double c = m(0) * q1 / (q2 * l);
  const Row12 d_c = m(0) * (d_q1 / (q2 * l) - q1 * d_q2 / (q2 * q2 * l) - q1 * d_l / (q2 * l * l));
  const Eigen::Vector3d bending = m(1) * r3 - m(2) * r2;
  const Mat3x12 d_t = r3 * d_c + c * d_r3 + (m(1) * d_r3 - m(2) * d_r2) / l - bending * d_l / (l * l);
  auto d_twist = [&](const Eigen::Vector3d& qi, const Mat3x12& d_qi) -> Mat3x12 {
    return m(0) / (2.0 * q2) * (-skew(r3) * d_qi + skew(qi) * d_r3) - m(0) / (2.0 * q2 * q2) * qi.cross(r3) * d_q2;
  };
  kg.block<3, 12>(0, 0) -= d_t;
  kg.block<3, 12>(3, 0) -= d_twist(qa, d_qa);
  kg.block<3, 12>(6, 0) += d_t;
  kg.block<3, 12>(9, 0) -= d_twist(qb, d_qb);
  return out;
}

}  // namespace scopekin::model
