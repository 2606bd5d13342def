#include "model/colon/colon_compliance.hpp"

#include "model/model_error.hpp"

namespace scopekin::model {

ColonCompliance::ColonCompliance(const ColonStructure& colon) : nodes_(colon.beam.node_count()) {
    ScopeBeam::Assembly assembly;
    colon.beam.assemble(assembly, true);
    BlockTridiagonalMatrix stiffness = assembly.tangent;
    colon.loads.add_spring_stiffness(stiffness);
    std::vector<bool> clamped(6 * nodes_, false);
    for (const NodeSupport& s : colon.supports) {
        for (std::size_t c = 0; c < 3; ++c)
            if (s.fixed_translation[c]) clamped[6 * s.node + c] = true;
        if (s.fixed_rotation)
            for (std::size_t c = 3; c < 6; ++c)
                clamped[6 * s.node + c] = true;
    }
    for (std::size_t dof = 0; dof < clamped.size(); ++dof)
        if (clamped[dof]) stiffness.constrain_dof(dof);
    BlockTridiagonalSolver solver;
    if (!solver.factorize(stiffness))
        throw ModelError(
            "colon: the colon structure is not held (its stiffness matrix is singular); every "
            "stretch "
            "must be fixed or hang on a mesentery");
    const auto m = static_cast<Eigen::Index>(3 * nodes_);
    compliance_.resize(m, m);
    Eigen::VectorXd unit = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * nodes_));
    for (std::size_t j = 0; j < nodes_; ++j) {
        for (std::size_t c = 0; c < 3; ++c) {
            const std::size_t dof = 6 * j + c;
            if (clamped[dof]) {
                compliance_.col(static_cast<Eigen::Index>(3 * j + c)).setZero();
                continue;
            }
            unit(static_cast<Eigen::Index>(dof)) = 1.0;
            Eigen::VectorXd u = solver.solve(unit);
            unit(static_cast<Eigen::Index>(dof)) = 0.0;
            for (std::size_t d = 0; d < 6 * nodes_; ++d)
                if (clamped[d]) u(static_cast<Eigen::Index>(d)) = 0.0;
            for (std::size_t i = 0; i < nodes_; ++i)
                compliance_.block<3, 1>(static_cast<Eigen::Index>(3 * i),
                                        static_cast<Eigen::Index>(3 * j + c)) =
                    u.segment<3>(static_cast<Eigen::Index>(6 * i));
        }
    }
    if (!compliance_.allFinite()) throw ModelError("colon: the colon's compliance is not finite");
    blocks_.resize(nodes_ * nodes_);
    for (std::size_t i = 0; i < nodes_; ++i)
        for (std::size_t j = 0; j < nodes_; ++j)
            blocks_[i * nodes_ + j] = compliance_.block<3, 3>(static_cast<Eigen::Index>(3 * i),
                                                              static_cast<Eigen::Index>(3 * j));
}

Eigen::Matrix3d ColonCompliance::point_block(std::size_t sa, double wa, std::size_t sb,
                                             double wb) const {
    return (1.0 - wa) * ((1.0 - wb) * node_block(sa, sb) + wb * node_block(sa, sb + 1)) +
           wa * ((1.0 - wb) * node_block(sa + 1, sb) + wb * node_block(sa + 1, sb + 1));
}

Eigen::Vector3d ColonCompliance::point_displacement(
    std::size_t segment, double weight, const std::vector<ColonPointForce>& forces) const {
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (const ColonPointForce& f : forces)
        u += point_block(segment, weight, f.segment, f.weight) * f.force_N;
    return u;
}

void ColonCompliance::displacement(const std::vector<ColonPointForce>& forces,
                                   std::vector<Eigen::Vector3d>& displacement_mm) const {
    Eigen::VectorXd load = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * nodes_));
    for (const ColonPointForce& f : forces) {
        load.segment<3>(static_cast<Eigen::Index>(3 * f.segment)) += (1.0 - f.weight) * f.force_N;
        load.segment<3>(static_cast<Eigen::Index>(3 * f.segment + 3)) += f.weight * f.force_N;
    }
    const Eigen::VectorXd u = compliance_ * load;
    displacement_mm.resize(nodes_);
    for (std::size_t i = 0; i < nodes_; ++i)
        displacement_mm[i] = u.segment<3>(static_cast<Eigen::Index>(3 * i));
}

Eigen::Vector3d ColonCompliance::node_displacement(
    std::size_t node, const std::vector<ColonPointForce>& forces) const {
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (const ColonPointForce& f : forces)
        u += node_block(node, f.segment) * ((1.0 - f.weight) * f.force_N) +
             node_block(node, f.segment + 1) * (f.weight * f.force_N);
    return u;
}

}  // namespace scopekin::model
