#pragma once
// sigmoid_mobility's load from the screening's six unit-load runs (a unit load along x, y and z,
// sine and cosine): the load u sin(w t) + v cos(w t) is linear in the 6-vector (u, v), so least
// squares on the six runs' Jacobian gives it, and the SVD of the 3 x 2 matrix [u v] the best
// single direction d with u = a d, v = b d (a rank-one approximation: Eckart & Young 1936,
// Psychometrika 1(3)). The candidate's parameters are then (a, b) = (A cos phi, A sin phi) and d
// as polar and azimuth angles.
#include <limits>

#include <Eigen/Dense>

namespace scopekin::discrepancy {

struct SigmoidLoad {
    bool ok = false;
    Eigen::Vector3d direction = Eigen::Vector3d::UnitY();  ///< unit, largest component positive
    double a = 0, b = 0;  ///< [N/mm] the sine's and the cosine's amplitude along `direction`
    /// Columns for (a, b) along the direction, and zero columns for its two angles (the angles do
    /// nothing at zero amplitude): the neutral Jacobian of the candidate's four parameters.
    Eigen::MatrixXd jacobian_along_direction;
    /// The cost the load predicts, linearly, on the rows its least squares used:
    /// |w .* (r0 + J_dir (a, b))|^2.
    double predicted_cost = std::numeric_limits<double>::infinity();
};

/// The least-squares load of the six unit-load columns `J` (order (u_x, v_x, u_y, v_y, u_z, v_z),
/// per N/mm) against the residual `r0`, on the rows weighted by `row_weight` (0 leaves a row out),
/// along its best single direction, a and b clamped to [amplitude_lo, amplitude_hi]. Not ok if the
/// sizes differ or the load is zero.
SigmoidLoad load_along_direction(const Eigen::MatrixXd& J, const Eigen::VectorXd& r0,
                                 const Eigen::VectorXd& row_weight, double amplitude_lo,
                                 double amplitude_hi);

}  // namespace scopekin::discrepancy
