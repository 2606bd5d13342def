#pragma once
// Linear 3D Timoshenko beam element, 2 nodes x 6 DOF, in its local frame (x along the
// element). DOF order: [u v w theta_x theta_y theta_z] at node 1, then node 2.
// These are the small-strain matrices; large rotations are handled by the co-rotational
// wrapper (corotational_element.hpp), which applies them in a frame that moves with the element.
#include <Eigen/Dense>

#include "model/beam/beam_section.hpp"

namespace scopekin::model {

using Mat12 = Eigen::Matrix<double, 12, 12>;
using Vec12 = Eigen::Matrix<double, 12, 1>;

/// Stiffness [N/mm, N, N mm] of thesis Eq. (4.2) / App. E with the shear parameters
/// phi_y = 12 E I_z / (kappa G A_sy l^2), phi_z = 12 E I_y / (kappa G A_sz l^2)
/// (Przemieniecki 1968, Sec. 5.6; the printed Eq. 4.2 has index typos, App. E's derivation is followed).
Mat12 timoshenko_local_stiffness(const BeamSection& section, double length_mm);

/// Consistent mass [t, t mm, t mm^2] with rotary inertia, thesis Eq. (4.5) as coded in App. H
/// (App. H uses I_z in entry (3,5) where symmetry requires I_y; I_y is used here).
Mat12 timoshenko_local_mass(const BeamSection& section, double length_mm);

/// Reference local frame of an element from node a to node b, thesis Eq. (4.3) / App. F:
/// columns e1 (along the element), e2 (horizontal, e2 = z x e1 normalised), e3 = e1 x e2.
/// Vertical element (along global +/-z): App. F's special case, e2 = global y.
Eigen::Matrix3d reference_element_frame(const Eigen::Vector3d& node_a_mm,
                                        const Eigen::Vector3d& node_b_mm);

}  // namespace scopekin::model
