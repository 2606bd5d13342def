#pragma once
// 3D co-rotational beam element (Crisfield 1990; Battini & Pacoste 2002, CMAME 191:1755).
//
// Why co-rotational: the scope bends through 180 deg and more, but each 1 cm element only
// deforms a little relative to its own chord. The element's rigid motion is split off with a
// local frame R_r that follows the chord; in that frame the small-strain Timoshenko matrices
// of Eq. (4.2) stay valid. The thesis (Eq. 4.1) re-assembles K on the "updated" positions every
// step; the co-rotational split is the exact form of that idea: equilibrium is satisfied in the
// deformed configuration, and rotations are stored as matrices, so no angle ever wraps.
//
// Global element variables (12): [dx_a, dw_a, dx_b, dw_b], translations in mm and spatial
// spins in rad (dR = S(dw) R). Local deformation (7): [u (elongation, mm), theta_a, theta_b
// (rad, node rotations relative to the chord frame)].
#include <Eigen/Dense>

#include "model/beam/beam_section.hpp"
#include "model/beam/timoshenko_element.hpp"

namespace scopekin::model {

using Vec7 = Eigen::Matrix<double, 7, 1>;
using Mat7 = Eigen::Matrix<double, 7, 7>;
using Mat7x12 = Eigen::Matrix<double, 7, 12>;

/// What an element remembers of its stress-free configuration.
struct CorotationalReference {
    double length_mm = 0;
    Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();  ///< E0: reference local frame (Eq. 4.3)
    Mat7 local_stiffness;  ///< Eq. (4.2) restricted to the 7 deformational DOFs [u2, th_a, th_b]
    Mat12 local_mass;      ///< Eq. (4.5), local frame
    /// The deformation at which the element carries no force (zero: straight and unstrained).
    /// A bending section angulated by its wires holds a curvature: rest_curvature_deformation.
    Vec7 rest_deformation = Vec7::Zero();
};

/// The rest deformation of an element of length `length_mm` bent to the uniform curvature
/// `curvature_local_per_mm` (local components [1/mm]; its axial part, a twist, is dropped): the
/// arc's end tangents turn by -kappa L / 2 and +kappa L / 2 about the bending axis relative to its
/// chord. The chord keeps its length (as under an end moment, the element's chord stands for its
/// arc): a section bent so and pulled straight again is as long as before.
Vec7 rest_curvature_deformation(const Eigen::Vector3d& curvature_local_per_mm, double length_mm);

CorotationalReference make_corotational_reference(const BeamSection& section,
                                                  const Eigen::Vector3d& node_a_mm,
                                                  const Eigen::Vector3d& node_b_mm);

/// Current kinematics of one element.
struct CorotationalKinematics {
    Eigen::Matrix3d frame;  ///< R_r = [r1 r2 r3], r1 along the current chord
    double length_mm = 0;
    Vec7 deformation;  ///< [u mm, theta_a rad (3), theta_b rad (3)]
    Mat7x12 b_matrix;  ///< d(deformation) / d(global variables)
};

/// Node rotations are total rotations from the reference configuration (identity at start).
CorotationalKinematics corotational_kinematics(const CorotationalReference& ref,
                                               const Eigen::Vector3d& x_a_mm,
                                               const Eigen::Matrix3d& rotation_a,
                                               const Eigen::Vector3d& x_b_mm,
                                               const Eigen::Matrix3d& rotation_b);

struct CorotationalResponse {
    CorotationalKinematics kinematics;
    Vec7 local_force;        ///< [N (N), m_a (N mm), m_b (N mm)]
    Vec12 internal_force;    ///< global [f_a N, m_a N mm, f_b, m_b]
    Mat12 material_tangent;  ///< B^T K_l B (symmetric, positive semi-definite)
    Mat12
        geometric_tangent;  ///< d(B^T)/dq f_l: stress stiffening / softening of the rotating frame
};

/// Internal force and the exact consistent tangent (material + geometric, Battini & Pacoste
/// 2002 Sec. 5, derived here with global vectors; checked against finite differences in tests).
CorotationalResponse corotational_response(const CorotationalReference& ref,
                                           const Eigen::Vector3d& x_a_mm,
                                           const Eigen::Matrix3d& rotation_a,
                                           const Eigen::Vector3d& x_b_mm,
                                           const Eigen::Matrix3d& rotation_b, bool with_tangent);

using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9, Eigen::RowMajor>;
using Mat7x9 = Eigen::Matrix<double, 7, 9, Eigen::RowMajor>;  ///< row-major: rows are contiguous

/// The same response on the 9 variables [dx_a, dw_a, dw_b], the form the assembly uses.
/// Translating both nodes changes nothing, so the dx_b columns of B and of the tangents are
/// minus the dx_a columns; the element's forces balance, so the f_b row of the internal force
/// and of the tangents is minus the f_a row. Rows and columns are [x_a, w_a, w_b].
struct CorotationalReducedResponse {
    Eigen::Matrix3d frame;  ///< R_r
    double length_mm = 0;
    Vec7 deformation;
    Vec7 local_force;
    Mat7x9 b_matrix;
    Vec9 internal_force;     ///< [f_a, m_a, m_b]; f_b = -f_a
    Mat9 material_tangent;   ///< only filled with `with_tangent`
    Mat9 geometric_tangent;  ///< only filled with `with_tangent`
};

void corotational_response_reduced(const CorotationalReference& ref, const Eigen::Vector3d& x_a_mm,
                                   const Eigen::Matrix3d& rotation_a, const Eigen::Vector3d& x_b_mm,
                                   const Eigen::Matrix3d& rotation_b, bool with_tangent,
                                   CorotationalReducedResponse& out);

/// The co-rotating frame R_r alone (for the mass matrix).
Eigen::Matrix3d corotational_frame(const CorotationalReference& ref, const Eigen::Vector3d& x_a_mm,
                                   const Eigen::Matrix3d& rotation_a, const Eigen::Vector3d& x_b_mm,
                                   const Eigen::Matrix3d& rotation_b);

}  // namespace scopekin::model
