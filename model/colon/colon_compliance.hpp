#pragma once
// The colon's compliance on its centerline nodes: C = K_c^-1 restricted to node translations
// [mm/N], from the linear stiffness-only colon of thesis Eq. 4.16 (K_c U_c = F_c) with its
// clamps (fixed regions) and mesentery springs (mobile regions). K_c is the tangent of the
// unloaded structure, so C is constant and is computed once (3m solves of the banded K_c).
// It gives the colon's part of the Delassus operator (Eq. 4.24) and the colon's displacement
// under the contact forces. A contact point on segment j at weight w moves as
// (1 - w) u_j + w u_{j+1} and shares its force the same way; the wall's offset from the
// centerline (rotation of the colon's section) is neglected, like the radial deformation.
#include <Eigen/Dense>
#include <vector>

#include "model/colon/colon_beam.hpp"

namespace scopekin::model {

/// A force on the colon at a point of its centerline.
struct ColonPointForce {
    std::size_t segment = 0;
    double weight = 0;  ///< in [0, 1] along the segment
    Eigen::Vector3d force_N = Eigen::Vector3d::Zero();
};

class ColonCompliance {
public:
    /// Throws ModelError if the colon is not held (a region that is neither clamped nor on a
    /// mesentery spring makes K_c singular).
    explicit ColonCompliance(const ColonStructure& colon);
    std::size_t node_count() const { return nodes_; }
    /// Translational compliance between nodes i and j [mm/N].
    const Eigen::Matrix3d& node_block(std::size_t i, std::size_t j) const {
        return blocks_[i * nodes_ + j];
    }
    /// Compliance between two centerline points (segment, weight) [mm/N].
    Eigen::Matrix3d point_block(std::size_t segment_a, double weight_a, std::size_t segment_b,
                                double weight_b) const;
    /// Displacement of a centerline point (segment, weight) [mm] under the given point forces:
    /// the sum of point_block x force over the forces, in their order.
    Eigen::Vector3d point_displacement(std::size_t segment, double weight,
                                       const std::vector<ColonPointForce>& forces) const;
    /// Displacement of every node [mm] under the given point forces.
    void displacement(const std::vector<ColonPointForce>& forces,
                      std::vector<Eigen::Vector3d>& displacement_mm) const;
    /// Displacement of one node [mm] under the given point forces: the same sum as displacement()
    /// restricted to the node's rows, O(forces) instead of O(nodes^2) (the sensors read one node
    /// every step).
    Eigen::Vector3d node_displacement(std::size_t node,
                                      const std::vector<ColonPointForce>& forces) const;

private:
    std::size_t nodes_ = 0;
    Eigen::MatrixXd compliance_;  ///< for displacement(): one matrix-vector product
    /// The same numbers as 3x3 blocks, node pair (i, j) at i * nodes_ + j: a point's block and
    /// its neighbour's are adjacent in memory (the contact assembly reads them pairwise; read
    /// from the 2.6 MB column-major matrix each block touched three cache lines).
    std::vector<Eigen::Matrix3d> blocks_;
};

}  // namespace scopekin::model
