#pragma once
// Where "truth" effects enter the world (the discrepancy workflow hides them in synthetic
// recordings and must later name them). An effect may change parameters once, when the world
// is built, add loads on the scope every step, and change the friction of each contact.
// The default of every hook is "no change", so an effect overrides only what it touches.
// All vectors are in the colon's (body) frame, in mm and N.
#include <array>
#include <string>
#include <vector>

#include "model/beam/beam_loads.hpp"
#include "model/beam/beam_section.hpp"
#include "model/colon/colon_region.hpp"

namespace scopekin::model {

/// What an effect may read about the world during a step.
struct WorldEffectView {
  double time_s = 0;                          ///< at the end of the step being computed
  double insertion_depth_mm = 0;
  std::vector<Eigen::Vector3d> scope_nodes_mm;  ///< body frame, node 0 = handle, last = tip
  std::vector<double> arc_from_tip_mm;          ///< per scope node
};

class WorldEffect {
 public:
  virtual ~WorldEffect() = default;
  virtual std::string name() const = 0;
  /// Parameter changes, once at construction: the scope's element sections (node 0 side first).
  virtual void adjust_scope_sections(std::vector<BeamSection>& /*sections*/) const {}
  /// Parameter changes, once at construction: the colon's region properties.
  virtual void adjust_colon_properties(std::array<ColonRegionProperties, 8>& /*properties*/) const {}
  /// Extra loads on scope nodes at the end of the step (body frame) [N, N mm].
  virtual void add_scope_loads(const WorldEffectView& /*view*/, std::vector<NodalLoad>& /*loads*/) const {}
  /// Friction coefficient of one contact; `mu` is the scenario's value there.
  virtual double friction_coefficient(double /*arc_from_tip_mm*/, ColonRegion /*region*/, double mu) const {
    return mu;
  }
};

}  // namespace scopekin::model
