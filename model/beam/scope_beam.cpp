#include "model/beam/scope_beam.hpp"

#include <string>

#include "model/beam/rotation.hpp"
#include "model/model_error.hpp"

namespace scopekin::model {

ScopeBeam::ScopeBeam(std::vector<Eigen::Vector3d> nodes, std::vector<BeamSection> sections)
    : reference_nodes_(std::move(nodes)) {
  if (reference_nodes_.size() < 2)
    throw ModelError("nodes: a beam needs at least 2 nodes, got " + std::to_string(reference_nodes_.size()));
  const std::size_t elements = reference_nodes_.size() - 1;
  if (sections.size() == 1) sections.assign(elements, sections.front());
  if (sections.size() != elements)
    throw ModelError("sections: expected 1 or " + std::to_string(elements) + " sections, got " +
                     std::to_string(sections.size()));
  sections_ = std::move(sections);
  for (std::size_t i = 0; i < reference_nodes_.size(); ++i)
    for (int c = 0; c < 3; ++c)
      require_finite(reference_nodes_[i](c), "node " + std::to_string(i) + " coordinate " + "xyz"[c] + " (mm)");
  arc_length_.assign(reference_nodes_.size(), 0.0);
  for (std::size_t e = 0; e < elements; ++e) {
    const std::string where = "element " + std::to_string(e) + ": ";
    sections_[e].validate(where);
    const double length = (reference_nodes_[e + 1] - reference_nodes_[e]).norm();
    if (!(length > 1e-9))
      throw ModelError(where + "length " + std::to_string(length) + " mm must be > 0 (nodes " + std::to_string(e) +
                       " and " + std::to_string(e + 1) + " coincide)");
    references_.push_back(make_corotational_reference(sections_[e], reference_nodes_[e], reference_nodes_[e + 1]));
    arc_length_[e + 1] = arc_length_[e] + length;
  }
  reset_to_reference();
}

void ScopeBeam::reset_to_reference() {
  positions_ = reference_nodes_;
  rotations_.assign(reference_nodes_.size(), Eigen::Matrix3d::Identity());
}

void ScopeBeam::set_pose(std::size_t node, const Eigen::Vector3d& position_mm, const Eigen::Matrix3d& rotation) {
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
/// Eq. (4.6) on the updated configuration: the local mass rotated by the element's frame.
/// The rotation is block-diagonal (4 copies of the frame), so rotate the 16 3x3 blocks.
Mat12 global_mass(const Eigen::Matrix3d& frame, const Mat12& local_mass) {
  Mat12 m;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      m.block<3, 3>(3 * i, 3 * j) = frame * local_mass.block<3, 3>(3 * i, 3 * j) * frame.transpose();
  return m;
}
}  // namespace

void ScopeBeam::assemble(Assembly& out, bool with_tangent, BlockTridiagonalMatrix* mass) const {
  out.internal_force = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(dof_count()));
  if (with_tangent) {
    out.tangent.resize(node_count());
    out.material_tangent.resize(node_count());
  }
  if (mass != nullptr) mass->resize(node_count());
  for (std::size_t e = 0; e < element_count(); ++e) {
    const CorotationalResponse resp = corotational_response(references_[e], positions_[e], rotations_[e],
                                                            positions_[e + 1], rotations_[e + 1], with_tangent);
    out.internal_force.segment<12>(static_cast<Eigen::Index>(6 * e)) += resp.internal_force;
    if (with_tangent) {
      out.material_tangent.add_element(e, resp.material_tangent);
      out.tangent.add_element(e, resp.material_tangent + resp.geometric_tangent);
    }
    if (mass != nullptr) mass->add_element(e, global_mass(resp.kinematics.frame, references_[e].local_mass));
  }
}

void ScopeBeam::assemble_mass(BlockTridiagonalMatrix& mass) const {
  mass.resize(node_count());
  for (std::size_t e = 0; e < element_count(); ++e) {
    const CorotationalKinematics k = corotational_kinematics(references_[e], positions_[e], rotations_[e],
                                                             positions_[e + 1], rotations_[e + 1]);
    mass.add_element(e, global_mass(k.frame, references_[e].local_mass));
  }
}

Eigen::VectorXd ScopeBeam::gravity_load(const Eigen::Vector3d& g) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(dof_count()));
  for (std::size_t e = 0; e < element_count(); ++e) {
    const Eigen::Vector3d half_weight = 0.5 * sections_[e].mass_per_length_t_per_mm * references_[e].length_mm * g;
    f.segment<3>(static_cast<Eigen::Index>(6 * e)) += half_weight;
    f.segment<3>(static_cast<Eigen::Index>(6 * e + 6)) += half_weight;
  }
  return f;
}

double ScopeBeam::strain_energy_Nmm() const {
  double energy = 0.0;
  for (std::size_t e = 0; e < element_count(); ++e) {
    const CorotationalKinematics k = corotational_kinematics(references_[e], positions_[e], rotations_[e],
                                                             positions_[e + 1], rotations_[e + 1]);
    energy += 0.5 * k.deformation.dot(references_[e].local_stiffness * k.deformation);
  }
  return energy;
}

ScopeBeam straight_beam(const Eigen::Vector3d& start, const Eigen::Vector3d& direction, double length_mm,
                        std::size_t element_count, const BeamSection& section) {
  require_positive(length_mm, "length_mm");
  if (element_count == 0) throw ModelError("element_count: must be >= 1");
  if (!(direction.norm() > 0.0) || !direction.allFinite()) throw ModelError("direction: must be a non-zero finite vector");
  const Eigen::Vector3d d = direction.normalized();
  std::vector<Eigen::Vector3d> nodes;
  for (std::size_t i = 0; i <= element_count; ++i)
    nodes.push_back(start + d * (length_mm * static_cast<double>(i) / static_cast<double>(element_count)));
  return ScopeBeam(std::move(nodes), {section});
}

}  // namespace scopekin::model
