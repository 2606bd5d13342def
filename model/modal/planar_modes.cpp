#include "model/modal/planar_modes.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "model/model_error.hpp"

namespace scopekin::model {

std::vector<PlanarMode> planar_bending_modes(const ScopeBeam& beam, const RayleighDamping& damping,
                                             std::size_t count) {
    for (std::size_t i = 0; i < beam.node_count(); ++i)
        if (std::abs(beam.reference_position(i).y()) > 1e-9 ||
            std::abs(beam.reference_position(i).z()) > 1e-9)
            throw ModelError("planar_bending_modes: node " + std::to_string(i) +
                             " is off the x axis");
    // The modes of the reference configuration (header), whatever pose `beam` is in now.
    ScopeBeam reference = beam;
    reference.reset_to_reference();
    ScopeBeam::Assembly assembly;
    reference.assemble(assembly, true);
    BlockTridiagonalMatrix mass;
    reference.assemble_mass(mass);
    const Eigen::MatrixXd k_full = assembly.material_tangent.to_dense();
    const Eigen::MatrixXd m_full = mass.to_dense();
    std::vector<Eigen::Index> dofs;
    for (std::size_t node = 1; node < beam.node_count(); ++node) {
        dofs.push_back(static_cast<Eigen::Index>(6 * node + 1));  // u_y
        dofs.push_back(static_cast<Eigen::Index>(6 * node + 5));  // theta_z
    }
    const auto n = static_cast<Eigen::Index>(dofs.size());
    Eigen::MatrixXd k(n, n), m(n, n);
    for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index j = 0; j < n; ++j) {
            k(i, j) = k_full(dofs[static_cast<std::size_t>(i)], dofs[static_cast<std::size_t>(j)]);
            m(i, j) = m_full(dofs[static_cast<std::size_t>(i)], dofs[static_cast<std::size_t>(j)]);
        }
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(k, m);
    if (solver.info() != Eigen::Success)
        throw ModelError("planar_bending_modes: eigen solver failed");
    const Eigen::MatrixXd c =
        damping.mass_coefficient_per_s * m + damping.stiffness_coefficient_s * k;
    std::vector<PlanarMode> modes;
    for (Eigen::Index i = 0; i < n && modes.size() < count; ++i) {
        const double w = std::sqrt(std::max(0.0, solver.eigenvalues()(i)));
        const Eigen::VectorXd phi = solver.eigenvectors().col(i);
        PlanarMode mode;
        mode.frequency_hz = w / (2.0 * M_PI);
        mode.damping_ratio = phi.dot(c * phi) / (2.0 * w * phi.dot(m * phi));
        modes.push_back(mode);
    }
    return modes;
}

}  // namespace scopekin::model
