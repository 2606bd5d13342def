#include "model/beam/scope_beam.hpp"

#include <algorithm>

#include <string>

#include "model/beam/rotation.hpp"
#include "model/model_error.hpp"

namespace scopekin::model {

ScopeBeam::ScopeBeam(std::vector<Eigen::Vector3d> nodes, std::vector<BeamSection> sections)
    : reference_nodes_(std::move(nodes)) {
    if (reference_nodes_.size() < 2)
        throw ModelError("nodes: a beam needs at least 2 nodes, got " +
                         std::to_string(reference_nodes_.size()));
    const std::size_t elements = reference_nodes_.size() - 1;
    if (sections.size() == 1) sections.assign(elements, sections.front());
    if (sections.size() != elements)
        throw ModelError("sections: expected 1 or " + std::to_string(elements) + " sections, got " +
                         std::to_string(sections.size()));
    sections_ = std::move(sections);
    for (std::size_t i = 0; i < reference_nodes_.size(); ++i)
        for (int c = 0; c < 3; ++c)
            require_finite(reference_nodes_[i](c),
                           "node " + std::to_string(i) + " coordinate " + "xyz"[c] + " (mm)");
    arc_length_.assign(reference_nodes_.size(), 0.0);
    for (std::size_t e = 0; e < elements; ++e) {
        const std::string where = "element " + std::to_string(e) + ": ";
        sections_[e].validate(where);
        const double length = (reference_nodes_[e + 1] - reference_nodes_[e]).norm();
        if (!(length > 1e-9))
            throw ModelError(where + "length " + std::to_string(length) +
                             " mm must be > 0 (nodes " + std::to_string(e) + " and " +
                             std::to_string(e + 1) + " coincide)");
        references_.push_back(make_corotational_reference(sections_[e], reference_nodes_[e],
                                                          reference_nodes_[e + 1]));
        arc_length_[e + 1] = arc_length_[e] + length;
    }
    reset_to_reference();
}

void ScopeBeam::reset_to_reference() {
    positions_ = reference_nodes_;
    rotations_.assign(reference_nodes_.size(), Eigen::Matrix3d::Identity());
}

void ScopeBeam::set_pose(std::size_t node, const Eigen::Vector3d& position_mm,
                         const Eigen::Matrix3d& rotation) {
    positions_[node] = position_mm;
    rotations_[node] = rotation;
}

void ScopeBeam::restore(const Configuration& saved) {
    positions_ = saved.positions;
    rotations_ = saved.rotations;
}

void ScopeBeam::apply_increment(const Eigen::VectorXd& inc) {
    for (std::size_t i = 0; i < positions_.size(); ++i) {
        const auto r = static_cast<Eigen::Index>(6 * i);
        positions_[i] += inc.segment<3>(r);
        rotations_[i] = rotation_exp(inc.segment<3>(r + 3)) * rotations_[i];
        rotations_[i] = reorthonormalize(rotations_[i]);
    }
}

namespace {
// The element loop visits elements in order, so block (e, e) already holds element e-1's share
// when element e arrives, and blocks (e, e+1), (e+1, e), (e+1, e+1) are first touched by element
// e: they are assigned, and the matrices never need zeroing.

/// Adds a reduced element matrix (rows and columns [x_a, w_a, w_b], x_b = -x_a; see
/// CorotationalReducedResponse) to the chain.
void add_reduced_element(BlockTridiagonalMatrix& m, std::size_t e, const Mat9& k) {
    const auto kxx = k.block<3, 3>(0, 0), kxa = k.block<3, 3>(0, 3), kxb = k.block<3, 3>(0, 6);
    const auto kax = k.block<3, 3>(3, 0), kaa = k.block<3, 3>(3, 3), kab = k.block<3, 3>(3, 6);
    const auto kbx = k.block<3, 3>(6, 0), kba = k.block<3, 3>(6, 3), kbb = k.block<3, 3>(6, 6);
    Mat6& d0 = m.diagonal(e);
    if (e == 0) d0.setZero();
    d0.block<3, 3>(0, 0) += kxx;
    d0.block<3, 3>(0, 3) += kxa;
    d0.block<3, 3>(3, 0) += kax;
    d0.block<3, 3>(3, 3) += kaa;
    Mat6& up = m.upper(e);
    up.block<3, 3>(0, 0) = -kxx;
    up.block<3, 3>(0, 3) = kxb;
    up.block<3, 3>(3, 0) = -kax;
    up.block<3, 3>(3, 3) = kab;
    Mat6& lo = m.lower(e);
    lo.block<3, 3>(0, 0) = -kxx;
    lo.block<3, 3>(0, 3) = -kxa;
    lo.block<3, 3>(3, 0) = kbx;
    lo.block<3, 3>(3, 3) = kba;
    Mat6& d1 = m.diagonal(e + 1);
    d1.block<3, 3>(0, 0) = kxx;
    d1.block<3, 3>(0, 3) = -kxb;
    d1.block<3, 3>(3, 0) = -kbx;
    d1.block<3, 3>(3, 3) = kbb;
}

/// Eq. (4.6) on the updated configuration: the local mass rotated by the element's frame. The
/// rotation is block-diagonal (4 copies of the frame), so each 3x3 block is R M_ij R^T; the
/// local mass is symmetric, so the blocks below the diagonal are transposes.
void add_element_mass(BlockTridiagonalMatrix& mass, std::size_t e, const Eigen::Matrix3d& frame,
                      const Mat12& local_mass) {
    Mat6& d0 = mass.diagonal(e);
    Mat6& up = mass.upper(e);
    Mat6& lo = mass.lower(e);
    Mat6& d1 = mass.diagonal(e + 1);
    if (e == 0) d0.setZero();
    for (int i = 0; i < 4; ++i)
        for (int j = i; j < 4; ++j) {
            const Eigen::Matrix3d fm = frame * local_mass.block<3, 3>(3 * i, 3 * j);
            Eigen::Matrix3d g;
            g.noalias() = fm * frame.transpose();
            // Block (i, j) of the 12x12 element matrix, and its mirror (j, i) = (i, j)^T.
            const int bi = i % 2, bj = j % 2;
            if (j < 2) {
                d0.block<3, 3>(3 * bi, 3 * bj) += g;
                if (i != j) d0.block<3, 3>(3 * bj, 3 * bi) += g.transpose();
            } else if (i >= 2) {
                d1.block<3, 3>(3 * bi, 3 * bj) = g;
                if (i != j) d1.block<3, 3>(3 * bj, 3 * bi) = g.transpose();
            } else {
                up.block<3, 3>(3 * bi, 3 * bj) = g;
                lo.block<3, 3>(3 * bj, 3 * bi) = g.transpose();
            }
        }
}

void ensure_blocks(BlockTridiagonalMatrix& m, std::size_t blocks) {
    if (m.block_count() != blocks) m.resize(blocks);
}
}  // namespace

void ScopeBeam::assemble(Assembly& out, bool with_tangent, BlockTridiagonalMatrix* mass,
                         std::size_t first_element) const {
    const auto dofs = static_cast<Eigen::Index>(dof_count());
    if (out.internal_force.size() != dofs) out.internal_force.resize(dofs);
    out.internal_force.setZero();
    if (with_tangent) {
        ensure_blocks(out.tangent, node_count());
        ensure_blocks(out.material_tangent, node_count());
    }
    if (mass != nullptr) ensure_blocks(*mass, node_count());
    // Skipped elements contribute nothing: clear their blocks (the loop below assigns blocks that
    // element e touches first, so only the ones before first_element can hold stale values).
    first_element = std::min(first_element, element_count());
    if (first_element > 0) {
        for (BlockTridiagonalMatrix* m : {with_tangent ? &out.tangent : nullptr,
                                          with_tangent ? &out.material_tangent : nullptr, mass}) {
            if (m == nullptr) continue;
            for (std::size_t i = 0; i <= first_element && i < node_count(); ++i)
                m->diagonal(i).setZero();
            for (std::size_t i = 0; i < first_element; ++i) {
                m->upper(i).setZero();
                m->lower(i).setZero();
            }
        }
    }
    CorotationalReducedResponse resp;
    Mat9 tangent;
    for (std::size_t e = first_element; e < element_count(); ++e) {
        corotational_response_reduced(references_[e], positions_[e], rotations_[e],
                                      positions_[e + 1], rotations_[e + 1], with_tangent, resp);
        const auto r = static_cast<Eigen::Index>(6 * e);
        out.internal_force.segment<6>(r) += resp.internal_force.head<6>();
        out.internal_force.segment<3>(r + 6) -= resp.internal_force.head<3>();  // f_b = -f_a
        out.internal_force.segment<3>(r + 9) += resp.internal_force.tail<3>();
        if (with_tangent) {
            add_reduced_element(out.material_tangent, e, resp.material_tangent);
            tangent = resp.material_tangent + resp.geometric_tangent;
            add_reduced_element(out.tangent, e, tangent);
        }
        if (mass != nullptr) add_element_mass(*mass, e, resp.frame, references_[e].local_mass);
    }
}

void ScopeBeam::set_rest_curvature(std::size_t element, const Eigen::Vector3d& curvature_per_mm) {
    CorotationalReference& ref = references_.at(element);
    if (curvature_per_mm.isZero(0.0)) {
        ref.rest_deformation.setZero();
        return;
    }
    const Eigen::Matrix3d frame =
        corotational_frame(ref, positions_[element], rotations_[element], positions_[element + 1],
                           rotations_[element + 1]);
    ref.rest_deformation =
        rest_curvature_deformation(frame.transpose() * curvature_per_mm, ref.length_mm);
}

void ScopeBeam::assemble_mass(BlockTridiagonalMatrix& mass) const {
    ensure_blocks(mass, node_count());
    for (std::size_t e = 0; e < element_count(); ++e)
        add_element_mass(mass, e,
                         corotational_frame(references_[e], positions_[e], rotations_[e],
                                            positions_[e + 1], rotations_[e + 1]),
                         references_[e].local_mass);
}

Eigen::VectorXd ScopeBeam::gravity_load(const Eigen::Vector3d& g) const {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(dof_count()));
    for (std::size_t e = 0; e < element_count(); ++e) {
        const Eigen::Vector3d half_weight =
            0.5 * sections_[e].mass_per_length_t_per_mm * references_[e].length_mm * g;
        f.segment<3>(static_cast<Eigen::Index>(6 * e)) += half_weight;
        f.segment<3>(static_cast<Eigen::Index>(6 * e + 6)) += half_weight;
    }
    return f;
}

double ScopeBeam::strain_energy_Nmm() const {
    double energy = 0.0;
    for (std::size_t e = 0; e < element_count(); ++e) {
        const CorotationalKinematics k = corotational_kinematics(
            references_[e], positions_[e], rotations_[e], positions_[e + 1], rotations_[e + 1]);
        const Vec7 strain = k.deformation - references_[e].rest_deformation;
        energy += 0.5 * strain.dot(references_[e].local_stiffness * strain);
    }
    return energy;
}

ScopeBeam straight_beam(const Eigen::Vector3d& start, const Eigen::Vector3d& direction,
                        double length_mm, std::size_t element_count, const BeamSection& section) {
    require_positive(length_mm, "length_mm");
    if (element_count == 0) throw ModelError("element_count: must be >= 1");
    if (!(direction.norm() > 0.0) || !direction.allFinite())
        throw ModelError("direction: must be a non-zero finite vector");
    const Eigen::Vector3d d = direction.normalized();
    std::vector<Eigen::Vector3d> nodes;
    for (std::size_t i = 0; i <= element_count; ++i)
        nodes.push_back(
            start + d * (length_mm * static_cast<double>(i) / static_cast<double>(element_count)));
    return ScopeBeam(std::move(nodes), {section});
}

}  // namespace scopekin::model
