#pragma once
// Small-vibration modes of a straight beam lying along global x, clamped at node 0, bending in
// the x-y plane: the generalized eigenproblem K phi = w^2 M phi on the DOFs (u_y, theta_z) of the
// free nodes (for a straight beam they decouple exactly from axial, torsion and x-z bending).
// K is the tangent at the reference configuration (unstressed, so purely material).
#include <vector>

#include "model/beam/scope_beam.hpp"
#include "model/solvers/rayleigh_damping.hpp"

namespace scopekin::model {

struct PlanarMode {
    double frequency_hz = 0;
    /// Modal damping ratio phi^T C phi / (2 w phi^T M phi) with the model's damping matrix
    /// C = a' M + b' K assembled the same way as in the dynamic solver.
    double damping_ratio = 0;
};

/// The lowest `count` modes; throws ModelError if the beam is not straight along x.
std::vector<PlanarMode> planar_bending_modes(const ScopeBeam& beam, const RayleighDamping& damping,
                                             std::size_t count);

}  // namespace scopekin::model
