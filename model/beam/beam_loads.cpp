#include "model/beam/beam_loads.hpp"

#include <set>
#include <string>

#include "model/beam/rotation.hpp"
#include "model/model_error.hpp"

namespace scopekin::model {

Eigen::VectorXd BeamLoads::assemble(const ScopeBeam& beam) const {
    for (int c = 0; c < 3; ++c)
        require_finite(gravity_mm_per_s2(c), std::string("gravity_mm_per_s2.") + "xyz"[c]);
    Eigen::VectorXd f = beam.gravity_load(gravity_mm_per_s2);
    for (std::size_t k = 0; k < nodal.size(); ++k) {
        const std::string where = "loads[" + std::to_string(k) + "]";
        if (nodal[k].node >= beam.node_count())
            throw ModelError(where + ".node: " + std::to_string(nodal[k].node) +
                             " is out of range (beam has " + std::to_string(beam.node_count()) +
                             " nodes)");
        for (int c = 0; c < 3; ++c) {
            require_finite(nodal[k].force_N(c), where + ".force_N." + "xyz"[c]);
            require_finite(nodal[k].moment_Nmm(c), where + ".moment_Nmm." + "xyz"[c]);
        }
        const auto r = static_cast<Eigen::Index>(6 * nodal[k].node);
        f.segment<3>(r) += nodal[k].force_N;
        f.segment<3>(r + 3) += nodal[k].moment_Nmm;
    }
    for (std::size_t k = 0; k < springs.size(); ++k) {
        const std::string where = "springs[" + std::to_string(k) + "]";
        if (springs[k].node >= beam.node_count())
            throw ModelError(where + ".node: " + std::to_string(springs[k].node) +
                             " is out of range (beam has " + std::to_string(beam.node_count()) +
                             " nodes)");
        require_non_negative(springs[k].stiffness_N_per_mm, where + ".stiffness_N_per_mm");
        for (int c = 0; c < 3; ++c)
            require_finite(springs[k].anchor_mm(c), where + ".anchor_mm." + "xyz"[c]);
    }
    return f;
}

void BeamLoads::add_spring_forces(const ScopeBeam& beam, Eigen::VectorXd& force) const {
    for (const AnchorSpring& s : springs)
        force.segment<3>(static_cast<Eigen::Index>(6 * s.node)) +=
            s.stiffness_N_per_mm * (s.anchor_mm - beam.position(s.node));
}

void BeamLoads::add_spring_stiffness(BlockTridiagonalMatrix& tangent) const {
    for (const AnchorSpring& s : springs)
        tangent.diagonal(s.node).block<3, 3>(0, 0) +=
            s.stiffness_N_per_mm * Eigen::Matrix3d::Identity();
}

void validate_supports(const ScopeBeam& beam, const std::vector<NodeSupport>& supports) {
    std::set<std::size_t> seen;
    for (std::size_t k = 0; k < supports.size(); ++k) {
        const std::string where = "supports[" + std::to_string(k) + "]";
        const NodeSupport& s = supports[k];
        if (s.node >= beam.node_count())
            throw ModelError(where + ".node: " + std::to_string(s.node) +
                             " is out of range (beam has " + std::to_string(beam.node_count()) +
                             " nodes)");
        if (!seen.insert(s.node).second)
            throw ModelError(where + ".node: node " + std::to_string(s.node) +
                             " is supported twice");
        if (s.target_position_mm && !s.target_position_mm->allFinite())
            throw ModelError(where + ".target_position_mm: not finite");
        if (s.target_rotation) {
            const Eigen::Matrix3d& r = *s.target_rotation;
            if (!r.allFinite() || (r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
                r.determinant() < 0.0)
                throw ModelError(where + ".target_rotation: not a rotation matrix");
        }
    }
}

SupportStart record_support_start(const ScopeBeam& beam, const std::vector<NodeSupport>& supports) {
    SupportStart start;
    for (const NodeSupport& s : supports) {
        start.positions.push_back(beam.position(s.node));
        start.rotations.push_back(beam.rotation(s.node));
    }
    return start;
}

SupportMotion support_motion(const ScopeBeam& beam, const std::vector<NodeSupport>& supports,
                             const SupportStart& start, double fraction) {
    SupportMotion m;
    for (std::size_t k = 0; k < supports.size(); ++k) {
        const NodeSupport& s = supports[k];
        const Eigen::Vector3d target_position =
            s.target_position_mm
                ? Eigen::Vector3d(start.positions[k] +
                                  fraction * (*s.target_position_mm - start.positions[k]))
                : start.positions[k];
        for (int c = 0; c < 3; ++c) {
            if (!s.fixed_translation[static_cast<std::size_t>(c)]) continue;
            m.dofs.push_back(6 * s.node + static_cast<std::size_t>(c));
            m.remaining_increment.push_back(target_position(c) - beam.position(s.node)(c));
        }
        if (s.fixed_rotation) {
            Eigen::Matrix3d target_rotation = start.rotations[k];
            if (s.target_rotation) {
                const Eigen::Vector3d total =
                    rotation_log(*s.target_rotation * start.rotations[k].transpose());
                target_rotation = rotation_exp(fraction * total) * start.rotations[k];
            }
            const Eigen::Vector3d spin =
                rotation_log(target_rotation * beam.rotation(s.node).transpose());
            for (int c = 0; c < 3; ++c) {
                m.dofs.push_back(6 * s.node + 3 + static_cast<std::size_t>(c));
                m.remaining_increment.push_back(spin(c));
            }
        }
    }
    return m;
}

}  // namespace scopekin::model
