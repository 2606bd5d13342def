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

CorotationalReference make_corotational_reference(const BeamSection& section,
                                                  const Eigen::Vector3d& a,
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

Vec7 rest_curvature_deformation(const Eigen::Vector3d& curvature_local_per_mm, double length_mm) {
    Eigen::Vector3d bend = curvature_local_per_mm;
    bend.x() = 0.0;
    Vec7 rest = Vec7::Zero();
    rest.segment<3>(1) = -0.5 * length_mm * bend;
    rest.segment<3>(4) = 0.5 * length_mm * bend;
    return rest;
}

namespace {

using Mat3x9 = Eigen::Matrix<double, 3, 9, Eigen::RowMajor>;  // row-major: row operations vectorise
using Row9 = Eigen::Matrix<double, 1, 9>;

/// The co-rotating frame of an element and the matrix g giving its spin in local components,
/// w = g dq (Battini & Pacoste Eq. 33), written with global vectors: w1 from the mean second
/// axis q, w2 and w3 from the chord's rotation. g is kept on [x_a, w_a, w_b] (its x_b columns
/// are minus its x_a columns).
struct ElementFrame {
    Eigen::Matrix3d frame;
    double length_mm = 0;
    Eigen::Vector3d qa, qb, q;
    double q1 = 0, q2 = 0;
    Mat3x9 spin;
};

void element_frame(const CorotationalReference& ref, const Eigen::Vector3d& xa,
                   const Eigen::Matrix3d& ra, const Eigen::Vector3d& xb, const Eigen::Matrix3d& rb,
                   bool with_spin, ElementFrame& f) {
    const Eigen::Vector3d chord = xb - xa;
    const double l = chord.norm();
    f.length_mm = l;
    const Eigen::Vector3d r1 = chord / l;
    // Battini & Pacoste Eq. (17)-(19): the frame's twist follows the mean of the nodes' second axes.
    f.qa = ra * ref.frame.col(1);
    f.qb = rb * ref.frame.col(1);
    f.q = 0.5 * (f.qa + f.qb);
    Eigen::Vector3d r3 = r1.cross(f.q);
    r3.normalize();
    const Eigen::Vector3d r2 = r3.cross(r1);
    f.frame.col(0) = r1;
    f.frame.col(1) = r2;
    f.frame.col(2) = r3;
    if (!with_spin) return;
    f.q1 = f.q.dot(r1);
    f.q2 = f.q.dot(r2);  // > 0 by construction of r3
    f.spin.setZero();
    f.spin.block<1, 3>(0, 0) = (f.q1 / (f.q2 * l)) * r3.transpose();
    f.spin.block<1, 3>(0, 3) = (f.qa.cross(r3) / (2.0 * f.q2)).transpose();
    f.spin.block<1, 3>(0, 6) = (f.qb.cross(r3) / (2.0 * f.q2)).transpose();
    f.spin.block<1, 3>(1, 0) = r3.transpose() / l;
    f.spin.block<1, 3>(2, 0) = -r2.transpose() / l;
}

/// Scalar functions of t = |theta|, sharing one sin/cos pair of t/2 (tan(t/2) = sin/cos):
/// eta = (1 - (t/2)cot(t/2))/t^2 for T^-1 (Eq. 13) and for H, and mu = eta'(t)/t for H. The two
/// switch to their series at different t (1e-4 for T^-1, 1e-3 for H), as they always have.
struct ThetaFunctions {
    double eta_jacobian = 0;
    double eta = 0;
    double mu = 0;
};

ThetaFunctions theta_functions(double t) {
    ThetaFunctions out;
    const double eta_series = 1.0 / 12.0 + t * t / 720.0;
    const double mu_series = 1.0 / 360.0 + t * t / 7560.0;
    if (t < 1e-4) {
        out.eta_jacobian = out.eta = eta_series;
        out.mu = mu_series;
        return out;
    }
    const double half_sin = std::sin(0.5 * t);
    const double half_cos = std::cos(0.5 * t);
    const double eta = (1.0 - 0.5 * t * half_cos / half_sin) / (t * t);  // (t/2) / tan(t/2)
    out.eta_jacobian = eta;
    if (t < 1e-3) {
        out.eta = eta_series;
        out.mu = mu_series;
    } else {
        out.eta = eta;
        out.mu = (t * t + 4.0 * std::cos(t) + t * std::sin(t) - 4.0) /
                 (4.0 * t * t * t * t * half_sin * half_sin);
    }
    return out;
}

/// T^-1 = I - S/2 + eta S^2 (Battini & Pacoste 2002, Eq. 13), eta from theta_functions.
Eigen::Matrix3d jacobian_inverse(const Eigen::Vector3d& theta, double eta) {
    const Eigen::Matrix3d s = skew(theta);
    return Eigen::Matrix3d::Identity() - 0.5 * s + eta * (s * s);
}

/// d(T^-T(theta) v) / d(theta) for fixed v (Battini & Pacoste 2002, Eq. 56 without the trailing
/// T^-1, which B already carries): eta (theta v^T - 2 v theta^T + (theta.v) I)
/// + mu S(theta)^2 v theta^T - S(v)/2, eta = (1 - (t/2)cot(t/2))/t^2, mu = eta'(t)/t.
Eigen::Matrix3d moment_transform_derivative(const Eigen::Vector3d& theta, const Eigen::Vector3d& v,
                                            const ThetaFunctions& fn) {
    const Eigen::Vector3d s2v = theta.cross(theta.cross(v));
    return fn.eta * (theta * v.transpose() - 2.0 * v * theta.transpose() +
                     theta.dot(v) * Eigen::Matrix3d::Identity()) +
           fn.mu * s2v * theta.transpose() - 0.5 * skew(v);
}

/// Expands a 9-variable matrix [x_a, w_a, w_b] to the 12 variables [x_a, w_a, x_b, w_b].
template <int Rows>
Eigen::Matrix<double, Rows, 12> expand_columns(const Eigen::Matrix<double, Rows, 9>& m) {
    Eigen::Matrix<double, Rows, 12> out;
    out.template middleCols<6>(0) = m.template leftCols<6>();
    out.template middleCols<3>(6) = -m.template leftCols<3>();
    out.template middleCols<3>(9) = m.template rightCols<3>();
    return out;
}

Mat12 expand_square(const Mat9& m) {
    const Eigen::Matrix<double, 9, 12> cols = expand_columns<9>(m);
    Mat12 out;
    out.middleRows<6>(0) = cols.topRows<6>();
    out.middleRows<3>(6) = -cols.topRows<3>();
    out.middleRows<3>(9) = cols.bottomRows<3>();
    return out;
}

/// B^T K_l B as sums of rows of B. K_l (Eq. 4.2 restricted to the deformational DOFs) couples each
/// rotation component only with the same component at the other node, so most of its entries
/// are zero: those are skipped.
void material_tangent(const Mat7& k, const Mat7x9& b, Mat9& out) {
    Mat7x9 kb;
    for (int i = 0; i < 7; ++i) {
        Row9 row = Row9::Zero();
        for (int j = 0; j < 7; ++j)
            if (k(i, j) != 0.0) row += k(i, j) * b.row(j);
        kb.row(i) = row;
    }
    // Row j of B^T (K B) = sum_i B(i, j) (K B)_i: contiguous row operations.
    for (int j = 0; j < 9; ++j) {
        Row9 row = b(0, j) * kb.row(0);
        for (int i = 1; i < 7; ++i)
            row += b(i, j) * kb.row(i);
        out.row(j) = row;
    }
}

void geometric_tangent(const ElementFrame& f, const Eigen::Vector3d& theta_a,
                       const Eigen::Vector3d& theta_b, const ThetaFunctions& fn_a,
                       const ThetaFunctions& fn_b, const Eigen::Matrix3d& t_inv_a,
                       const Eigen::Matrix3d& t_inv_b, CorotationalReducedResponse& out) {
    // Geometric tangent: the variation of B^T f_l with f_l frozen. With m_i = T^-T(theta_i) f_theta_i
    // and spin_i = [.. R_r^T at node i ..] - g, f_g = N r^T + sum_i spin_i^T m_i, so
    //   K_geo = N D + sum_i [ -S(R_r m_i) R_r g (rows of node i's spin) + spin_i^T H_i B_theta_i ]
    //           - d(g^T (m_a + m_b))/dq,
    // D = d r / dq (chord direction), H_i = d(T^-T v)/d(theta) (Battini & Pacoste 2002, Sec. 5).
    // d(g^T m)/dq with m = m_a + m_b frozen: g^T m = [t; w_a; -t; w_b] with
    //   t = m1 q1/(q2 l) r3 + (m2 r3 - m3 r2)/l,   w_i = m1/(2 q2) (q_i x r3),
    // and every ingredient varies linearly: d r_j = -S(r_j) Omega dq (Omega = R_r g, the frame's
    // global spin), d q_i = -S(q_i) dw_i, d l = r1 . (dx_b - dx_a).
    //
    // Evaluated with the rows g_1, g_2, g_3 of g (g_2, g_3 only have x_a columns: r3/l, -r2/l) and
    // S(R_r v) R_r = R_r S(v): Omega = sum_k r_k g_k, so d r1 = r2 g_3 - r3 g_2, d r2 = r3 g_1 - r1 g_3,
    // d r3 = r1 g_2 - r2 g_1 and S(R_r m) Omega = sum_k R_r (m x e_k) g_k: outer products only.
    const Mat7x9& b = out.b_matrix;
    const Eigen::Vector3d r1 = f.frame.col(0), r2 = f.frame.col(1), r3 = f.frame.col(2);
    const Eigen::Vector3d& qa = f.qa;
    const Eigen::Vector3d& qb = f.qb;
    const double l = f.length_mm, q1 = f.q1, q2 = f.q2, q3 = f.q.dot(r3);
    const Row9 g1 = f.spin.row(0);
    const Eigen::Vector3d ga = f.spin.block<1, 3>(0, 3).transpose(),
                          gb = f.spin.block<1, 3>(0, 6).transpose();
    const double c1 = q1 / (q2 * l);
    const Eigen::Vector3d m_a = t_inv_a.transpose() * out.local_force.segment<3>(1);
    const Eigen::Vector3d m_b = t_inv_b.transpose() * out.local_force.segment<3>(4);
    const Eigen::Vector3d m = m_a + m_b;

    // X_i = H_i B_theta_i; spin_a^T X_a + spin_b^T X_b = R_r X_a (rows w_a) + R_r X_b (rows w_b)
    // - g^T (X_a + X_b).
    const Mat3x9 hb_a = moment_transform_derivative(theta_a, out.local_force.segment<3>(1), fn_a) *
                        b.block<3, 9>(1, 0);
    const Mat3x9 hb_b = moment_transform_derivative(theta_b, out.local_force.segment<3>(4), fn_b) *
                        b.block<3, 9>(4, 0);
    const Row9 hb0 = hb_a.row(0) + hb_b.row(0);
    const Row9 hb1 = hb_a.row(1) + hb_b.row(1);
    const Row9 hb2 = hb_a.row(2) + hb_b.row(2);

    // d q1 = r1^T d q + q^T d r1, d q2 = r2^T d q + q^T d r2, d q = (d q_a + d q_b)/2.
    Row9 d_q1;
    d_q1.head<3>() = -(q2 * r2 + q3 * r3).transpose() / l;
    d_q1.segment<3>(3) = 0.5 * qa.cross(r1).transpose();
    d_q1.segment<3>(6) = 0.5 * qb.cross(r1).transpose();
    Row9 d_q2 = q3 * g1;
    d_q2.head<3>() += q1 * r2.transpose() / l;
    d_q2.segment<3>(3) += 0.5 * qa.cross(r2).transpose();
    d_q2.segment<3>(6) += 0.5 * qb.cross(r2).transpose();
    const double c = m(0) * q1 / (q2 * l);
    Row9 d_c = m(0) * (d_q1 / (q2 * l) - q1 * d_q2 / (q2 * q2 * l));
    d_c.head<3>() += m(0) * q1 * r1.transpose() / (q2 * l * l);

    Mat9& kg = out.geometric_tangent;
    // Rows x_a: N D - g_x^T X - d t, d t = r3 d c + (c + m2/l) d r3 - (m3/l) d r2 - (m2 r3 - m3 r2) d l / l^2.
    const double cm = c + m(1) / l, sm = m(2) / l;
    const Eigen::Vector3d u = cm * r2 + sm * r3;
    const Eigen::Vector3d w = cm * r3 - sm * r2;
    const Eigen::Vector3d bending = m(1) * r3 - m(2) * r2;
    auto kx = kg.block<3, 9>(0, 0);
    kx.noalias() = u * g1;
    kx.noalias() -= r3 * (c1 * hb0 + hb1 / l + d_c);
    kx.noalias() += r2 * (hb2 / l);
    kx.leftCols<3>() +=
        out.local_force(0) * (Eigen::Matrix3d::Identity() - r1 * r1.transpose()) / l -
        r1 * (w / l).transpose() - bending * (r1 / (l * l)).transpose();

    // Rows w_i: R_r X_i - S(R_r m_i) Omega - g_i X - d w_i,
    // d w_i = m1/(2 q2) (-S(r3) d q_i + S(q_i) d r3) - m1/(2 q2^2) (q_i x r3) d q2.
    const double alpha = m(0) / (2.0 * q2), beta = m(0) / (2.0 * q2 * q2);
    auto rotation_rows = [&](Eigen::Index row, const Eigen::Vector3d& mi, const Eigen::Vector3d& qi,
                             const Eigen::Vector3d& gi, const Mat3x9& hb_i) {
        auto k = kg.block<3, 9>(row, 0);
        k.noalias() = f.frame * hb_i;
        const Eigen::Vector3d p = mi(1) * r3 - mi(2) * r2 + alpha * qi.cross(r2);
        k.noalias() += p * g1;
        k.noalias() -= gi * hb0;
        k.noalias() += (beta * qi.cross(r3)) * d_q2;
        k.leftCols<3>() += ((mi(1) * r1 - mi(0) * r2) * r2.transpose() -
                            (mi(0) * r3 - mi(2) * r1 + alpha * qi.cross(r1)) * r3.transpose()) /
                           l;
        k.block<3, 3>(0, row) -=
            alpha * (qi * r3.transpose() - r3.dot(qi) * Eigen::Matrix3d::Identity());
    };
    rotation_rows(3, m_a, qa, ga, hb_a);
    rotation_rows(6, m_b, qb, gb, hb_b);
}

}  // namespace

Eigen::Matrix3d corotational_frame(const CorotationalReference& ref, const Eigen::Vector3d& xa,
                                   const Eigen::Matrix3d& ra, const Eigen::Vector3d& xb,
                                   const Eigen::Matrix3d& rb) {
    ElementFrame f;
    element_frame(ref, xa, ra, xb, rb, false, f);
    return f.frame;
}

void corotational_response_reduced(const CorotationalReference& ref, const Eigen::Vector3d& xa,
                                   const Eigen::Matrix3d& ra, const Eigen::Vector3d& xb,
                                   const Eigen::Matrix3d& rb, bool with_tangent,
                                   CorotationalReducedResponse& out) {
    ElementFrame f;
    element_frame(ref, xa, ra, xb, rb, true, f);
    out.frame = f.frame;
    out.length_mm = f.length_mm;
    const Eigen::Matrix3d frame_t = f.frame.transpose();
    const Eigen::Vector3d theta_a = rotation_log(frame_t * ra * ref.frame);
    const Eigen::Vector3d theta_b = rotation_log(frame_t * rb * ref.frame);
    out.deformation(0) = f.length_mm - ref.length_mm;
    out.deformation.segment<3>(1) = theta_a;
    out.deformation.segment<3>(4) = theta_b;
    const ThetaFunctions fn_a = theta_functions(theta_a.norm());
    const ThetaFunctions fn_b = theta_functions(theta_b.norm());
    const Eigen::Matrix3d t_inv_a = jacobian_inverse(theta_a, fn_a.eta_jacobian);
    const Eigen::Matrix3d t_inv_b = jacobian_inverse(theta_b, fn_b.eta_jacobian);

    // d theta_i = T^-1(theta_i) (R_r^T dw_i - w); spin_i = [.. R_r^T at node i ..] - g.
    Mat7x9& b = out.b_matrix;
    b.row(0).setZero();
    b.block<1, 3>(0, 0) = -f.frame.col(0).transpose();
    Mat3x9 spin_a = -f.spin;
    spin_a.block<3, 3>(0, 3) += frame_t;
    Mat3x9 spin_b = -f.spin;
    spin_b.block<3, 3>(0, 6) += frame_t;
    b.block<3, 9>(1, 0).noalias() = t_inv_a * spin_a;
    b.block<3, 9>(4, 0).noalias() = t_inv_b * spin_b;
    out.local_force.noalias() = ref.local_stiffness * (out.deformation - ref.rest_deformation);
    // B^T f_l through a column-major copy of B: the same summation order as the 12-column
    // product it replaces, so converged solutions keep their last digits.
    const Eigen::Matrix<double, 7, 9> b_columns = b;
    out.internal_force.noalias() = b_columns.transpose() * out.local_force;
    if (!with_tangent) return;
    material_tangent(ref.local_stiffness, b, out.material_tangent);
    geometric_tangent(f, theta_a, theta_b, fn_a, fn_b, t_inv_a, t_inv_b, out);
}

CorotationalKinematics corotational_kinematics(const CorotationalReference& ref,
                                               const Eigen::Vector3d& xa, const Eigen::Matrix3d& ra,
                                               const Eigen::Vector3d& xb,
                                               const Eigen::Matrix3d& rb) {
    CorotationalReducedResponse r;
    corotational_response_reduced(ref, xa, ra, xb, rb, false, r);
    CorotationalKinematics k;
    k.frame = r.frame;
    k.length_mm = r.length_mm;
    k.deformation = r.deformation;
    k.b_matrix = expand_columns<7>(r.b_matrix);
    return k;
}

CorotationalResponse corotational_response(const CorotationalReference& ref,
                                           const Eigen::Vector3d& xa, const Eigen::Matrix3d& ra,
                                           const Eigen::Vector3d& xb, const Eigen::Matrix3d& rb,
                                           bool with_tangent) {
    CorotationalReducedResponse r;
    corotational_response_reduced(ref, xa, ra, xb, rb, with_tangent, r);
    CorotationalResponse out;
    out.kinematics.frame = r.frame;
    out.kinematics.length_mm = r.length_mm;
    out.kinematics.deformation = r.deformation;
    out.kinematics.b_matrix = expand_columns<7>(r.b_matrix);
    out.local_force = r.local_force;
    out.internal_force.segment<6>(0) = r.internal_force.head<6>();
    out.internal_force.segment<3>(6) = -r.internal_force.head<3>();
    out.internal_force.segment<3>(9) = r.internal_force.tail<3>();
    if (!with_tangent) return out;
    out.material_tangent = expand_square(r.material_tangent);
    out.geometric_tangent = expand_square(r.geometric_tangent);
    return out;
}

}  // namespace scopekin::model
