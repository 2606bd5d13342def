#include "model/beam/timoshenko_element.hpp"

#include <cmath>

namespace scopekin::model {

Mat12 timoshenko_local_stiffness(const BeamSection& s, double l) {
    Mat12 k = Mat12::Zero();
    const double ea = s.axial_stiffness_N / l;
    k(0, 0) = ea;
    k(0, 6) = -ea;
    k(6, 6) = ea;
    const double gj = s.torsional_stiffness_Nmm2 / l;
    k(3, 3) = gj;
    k(3, 9) = -gj;
    k(9, 9) = gj;
    // Bending in x-y (v, theta_z) with E I_z; 1/inf = 0 gives the Euler-Bernoulli limit.
    const double phi_y = 12.0 * s.bending_stiffness_z_Nmm2 / (s.shear_stiffness_y_N * l * l);
    const double ez = s.bending_stiffness_z_Nmm2 / (1.0 + phi_y);
    k(1, 1) = 12.0 * ez / (l * l * l);
    k(1, 5) = 6.0 * ez / (l * l);
    k(1, 7) = -12.0 * ez / (l * l * l);
    k(1, 11) = 6.0 * ez / (l * l);
    k(5, 5) = (4.0 + phi_y) * ez / l;
    k(5, 7) = -6.0 * ez / (l * l);
    k(5, 11) = (2.0 - phi_y) * ez / l;
    k(7, 7) = 12.0 * ez / (l * l * l);
    k(7, 11) = -6.0 * ez / (l * l);
    k(11, 11) = (4.0 + phi_y) * ez / l;
    // Bending in x-z (w, theta_y) with E I_y: a positive theta_y lowers w, hence the sign flips.
    const double phi_z = 12.0 * s.bending_stiffness_y_Nmm2 / (s.shear_stiffness_z_N * l * l);
    const double ey = s.bending_stiffness_y_Nmm2 / (1.0 + phi_z);
    k(2, 2) = 12.0 * ey / (l * l * l);
    k(2, 4) = -6.0 * ey / (l * l);
    k(2, 8) = -12.0 * ey / (l * l * l);
    k(2, 10) = -6.0 * ey / (l * l);
    k(4, 4) = (4.0 + phi_z) * ey / l;
    k(4, 8) = 6.0 * ey / (l * l);
    k(4, 10) = (2.0 - phi_z) * ey / l;
    k(8, 8) = 12.0 * ey / (l * l * l);
    k(8, 10) = 6.0 * ey / (l * l);
    k(10, 10) = (4.0 + phi_z) * ey / l;
    return k.selfadjointView<Eigen::Upper>();
}

Mat12 timoshenko_local_mass(const BeamSection& s, double l) {
    Mat12 m = Mat12::Zero();
    const double rho_a = s.mass_per_length_t_per_mm;
    if (rho_a == 0.0) return m;
    const double rz2 = s.rotary_inertia_z_t_mm / rho_a;  // I_z / A [mm^2]
    const double ry2 = s.rotary_inertia_y_t_mm / rho_a;  // I_y / A
    const double rx2 = s.polar_inertia_t_mm / rho_a;     // J / A
    const double l2 = l * l;
    m(0, 0) = 1.0 / 3.0;
    m(0, 6) = 1.0 / 6.0;
    m(6, 6) = 1.0 / 3.0;
    m(1, 1) = 13.0 / 35.0 + 6.0 * rz2 / (5.0 * l2);
    m(1, 5) = 11.0 * l / 210.0 + rz2 / (10.0 * l);
    m(1, 7) = 9.0 / 70.0 - 6.0 * rz2 / (5.0 * l2);
    m(1, 11) = -13.0 * l / 420.0 + rz2 / (10.0 * l);
    m(2, 2) = 13.0 / 35.0 + 6.0 * ry2 / (5.0 * l2);
    m(2, 4) = -11.0 * l / 210.0 - ry2 / (10.0 * l);
    m(2, 8) = 9.0 / 70.0 - 6.0 * ry2 / (5.0 * l2);
    m(2, 10) = 13.0 * l / 420.0 - ry2 / (10.0 * l);
    m(3, 3) = rx2 / 3.0;
    m(3, 9) = rx2 / 6.0;
    m(9, 9) = rx2 / 3.0;
    m(4, 4) = l2 / 105.0 + 2.0 * ry2 / 15.0;
    m(4, 8) = -13.0 * l / 420.0 + ry2 / (10.0 * l);
    m(4, 10) = -l2 / 140.0 - ry2 / 30.0;
    m(5, 5) = l2 / 105.0 + 2.0 * rz2 / 15.0;
    m(5, 7) = 13.0 * l / 420.0 - rz2 / (10.0 * l);
    m(5, 11) = -l2 / 140.0 - rz2 / 30.0;
    m(7, 7) = 13.0 / 35.0 + 6.0 * rz2 / (5.0 * l2);
    m(7, 11) = -11.0 * l / 210.0 - rz2 / (10.0 * l);
    m(8, 8) = 13.0 / 35.0 + 6.0 * ry2 / (5.0 * l2);
    m(8, 10) = 11.0 * l / 210.0 + ry2 / (10.0 * l);
    m(10, 10) = l2 / 105.0 + 2.0 * ry2 / 15.0;
    m(11, 11) = l2 / 105.0 + 2.0 * rz2 / 15.0;
    const Mat12 full = m.selfadjointView<Eigen::Upper>();
    return rho_a * l * full;
}

Eigen::Matrix3d reference_element_frame(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const Eigen::Vector3d d = b - a;
    const double l = d.norm();
    const Eigen::Vector3d e1 = d / l;
    const double horizontal = std::hypot(e1.x(), e1.y());
    Eigen::Matrix3d frame;
    if (horizontal < 1e-12) {
        // App. F vertical case: Lambda = [0 0 +-1; 0 1 0; -+1 0 0] (rows are the local axes).
        const double sign = e1.z() > 0.0 ? 1.0 : -1.0;
        frame.col(0) = Eigen::Vector3d(0.0, 0.0, sign);
        frame.col(1) = Eigen::Vector3d(0.0, 1.0, 0.0);
        frame.col(2) = Eigen::Vector3d(-sign, 0.0, 0.0);
        return frame;
    }
    frame.col(0) = e1;
    frame.col(1) = Eigen::Vector3d(-e1.y() / horizontal, e1.x() / horizontal, 0.0);
    frame.col(2) =
        Eigen::Vector3d(-e1.x() * e1.z() / horizontal, -e1.y() * e1.z() / horizontal, horizontal);
    return frame;
}

}  // namespace scopekin::model
