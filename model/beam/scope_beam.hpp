#pragma once
// A chain of co-rotational Timoshenko elements: the colonoscope (or any slender beam).
// Node i joins elements i-1 and i. State: node positions (mm) and node rotations (total
// rotation from the reference configuration, as matrices). 6 DOF per node:
// [x y z (mm), spin about x y z (rad)], global frame.
#include <Eigen/Dense>
#include <vector>

#include "model/beam/beam_section.hpp"
#include "model/beam/corotational_element.hpp"
#include "model/linalg/block_tridiagonal.hpp"

namespace scopekin::model {

class ScopeBeam {
public:
    /// One section per element (sections.size() == nodes.size() - 1) or one for all.
    /// Throws ModelError naming the field for fewer than 2 nodes, non-finite coordinates,
    /// zero-length elements or unphysical sections.
    ScopeBeam(std::vector<Eigen::Vector3d> reference_nodes_mm, std::vector<BeamSection> sections);

    std::size_t node_count() const { return positions_.size(); }
    std::size_t element_count() const { return references_.size(); }
    std::size_t dof_count() const { return 6 * positions_.size(); }

    const Eigen::Vector3d& position(std::size_t node) const { return positions_[node]; }
    const Eigen::Matrix3d& rotation(std::size_t node) const { return rotations_[node]; }
    const Eigen::Vector3d& reference_position(std::size_t node) const {
        return reference_nodes_[node];
    }
    const BeamSection& section(std::size_t element) const { return sections_[element]; }
    const CorotationalReference& element_reference(std::size_t element) const {
        return references_[element];
    }
    /// Arc length from node 0 to `node` in the reference configuration [mm].
    double arc_length_mm(std::size_t node) const { return arc_length_[node]; }

    void set_pose(std::size_t node, const Eigen::Vector3d& position_mm,
                  const Eigen::Matrix3d& rotation);
    /// Bends `element` at rest to the uniform curvature `curvature_per_mm` (global frame, 1/mm:
    /// the bending axis times the curvature), resolved in the element's current frame; zero
    /// makes it straight again. Held until set again: a bending section angulated by its wires
    /// (model/scenario/tip_steering.hpp). Its axial part (a twist) is dropped.
    void set_rest_curvature(std::size_t element, const Eigen::Vector3d& curvature_per_mm);

    /// All node poses, to undo a rejected load step or time step.
    struct Configuration {
        std::vector<Eigen::Vector3d> positions;
        std::vector<Eigen::Matrix3d> rotations;
    };
    Configuration configuration() const { return {positions_, rotations_}; }
    void restore(const Configuration& saved);
    void reset_to_reference();
    /// x += dx, R = exp(S(dw)) R for every node; `increment` has 6 entries per node.
    void apply_increment(const Eigen::VectorXd& increment);

    struct Assembly {
        Eigen::VectorXd internal_force;           ///< [N, N mm] per DOF
        BlockTridiagonalMatrix tangent;           ///< material + geometric
        BlockTridiagonalMatrix material_tangent;  ///< B^T K_l B, for stiffness-proportional damping
    };
    /// Internal force, and with `with_tangent` the tangents; with `mass` also the mass matrix
    /// (same as assemble_mass, computed in the same pass over the elements).
    /// Elements before `first_element` are skipped (their blocks and forces are zero): the world
    /// leaves out the shaft outside the body, which the hand moves rigidly.
    void assemble(Assembly& out, bool with_tangent, BlockTridiagonalMatrix* mass = nullptr,
                  std::size_t first_element = 0) const;
    /// Consistent mass (Eq. 4.5) rotated into each element's current frame (Eq. 4.6 on the
    /// updated configuration). Gyroscopic terms are neglected (slow rotation rates).
    void assemble_mass(BlockTridiagonalMatrix& mass) const;
    /// Gravity as lumped nodal forces [N]: each element carries rho A g l / 2 to each node.
    Eigen::VectorXd gravity_load(const Eigen::Vector3d& gravity_mm_per_s2) const;
    /// Elastic strain energy [N mm] = sum 1/2 p_l^T K_l p_l.
    double strain_energy_Nmm() const;

private:
    std::vector<Eigen::Vector3d> reference_nodes_;
    std::vector<BeamSection> sections_;
    std::vector<CorotationalReference> references_;
    std::vector<double> arc_length_;
    std::vector<Eigen::Vector3d> positions_;
    std::vector<Eigen::Matrix3d> rotations_;
};

/// A straight beam from `start_mm` along `direction` of `length_mm` in `element_count` equal elements.
ScopeBeam straight_beam(const Eigen::Vector3d& start_mm, const Eigen::Vector3d& direction,
                        double length_mm, std::size_t element_count, const BeamSection& section);

}  // namespace scopekin::model
