#pragma once
// Loads and supports of a beam: gravity, nodal forces and moments, clamped nodes and nodes
// driven to a prescribed pose (the handle).
#include <Eigen/Dense>
#include <array>
#include <optional>
#include <vector>

#include "model/beam/scope_beam.hpp"

namespace scopekin::model {

struct NodalLoad {
    std::size_t node = 0;
    Eigen::Vector3d force_N = Eigen::Vector3d::Zero();
    Eigen::Vector3d moment_Nmm =
        Eigen::Vector3d::Zero();  ///< fixed in space (not a follower moment)
    /// The force's stiffness -dF/dx [N/mm] for a load that follows the node's position (a spring
    /// an effect adds). The world's step takes it implicitly: the force at the step's end is
    /// force_N - K (x_end - x_start), and K joins the step matrix, so a stiff spring cannot make
    /// the step unstable. Zero (the default): an explicit load. Static solves use springs
    /// (AnchorSpring) instead and ignore it.
    Eigen::Matrix3d stiffness_N_per_mm = Eigen::Matrix3d::Zero();
};

/// A linear spring [N/mm] pulling a node's position towards a fixed anchor point: the mesentery
/// holding a mobile colon region, or any elastic foundation. It is part of the structure, so a
/// static solve's load factor does not scale it.
struct AnchorSpring {
    std::size_t node = 0;
    Eigen::Vector3d anchor_mm = Eigen::Vector3d::Zero();
    double stiffness_N_per_mm = 0;
};

struct BeamLoads {
    Eigen::Vector3d gravity_mm_per_s2 = Eigen::Vector3d::Zero();
    std::vector<NodalLoad> nodal;
    std::vector<AnchorSpring> springs;
    /// Global load vector [N, N mm] of gravity and nodal loads (not the springs); throws ModelError
    /// naming a bad node index or non-finite value (springs included).
    Eigen::VectorXd assemble(const ScopeBeam& beam) const;
    /// Adds the springs' forces k (anchor - x) at the beam's current positions to `force`.
    void add_spring_forces(const ScopeBeam& beam, Eigen::VectorXd& force) const;
    /// Adds the springs' stiffness k I to the translational diagonal blocks of `tangent`.
    void add_spring_stiffness(BlockTridiagonalMatrix& tangent) const;
};

/// A clamp (all fixed, target = where the node is) or a prescribed pose (targets set).
struct NodeSupport {
    std::size_t node = 0;
    std::array<bool, 3> fixed_translation{true, true, true};
    bool fixed_rotation = true;
    std::optional<Eigen::Vector3d> target_position_mm;  ///< unset: hold the position it has
    std::optional<Eigen::Matrix3d> target_rotation;     ///< unset: hold the orientation it has
};

/// Throws ModelError naming the entry for an out-of-range node, a duplicated node or a
/// non-finite/non-orthonormal target.
void validate_supports(const ScopeBeam& beam, const std::vector<NodeSupport>& supports);

/// The DOFs a set of supports fixes, and the increment each still needs to reach the target
/// pose interpolated at `fraction` in [0, 1] between `start` poses and the targets.
struct SupportMotion {
    std::vector<std::size_t> dofs;
    std::vector<double> remaining_increment;
};

struct SupportStart {
    std::vector<Eigen::Vector3d> positions;
    std::vector<Eigen::Matrix3d> rotations;
};
SupportStart record_support_start(const ScopeBeam& beam, const std::vector<NodeSupport>& supports);
SupportMotion support_motion(const ScopeBeam& beam, const std::vector<NodeSupport>& supports,
                             const SupportStart& start, double fraction);

}  // namespace scopekin::model
