#pragma once
// The colon as a structure (thesis 4.3.1, Eq. 4.16-4.17): hollow-cylinder Timoshenko beams along
// the centerline, stiffness only (K_c U_c = F_c: no mass, no damping). Regions fixed to the
// retroperitoneum are clamped node by node; mobile regions (sigmoid, transverse) hang on their
// mesentery, modelled as springs pulling each node back to where it started.
#include <array>
#include <vector>

#include "model/beam/beam_loads.hpp"
#include "model/beam/scope_beam.hpp"
#include "model/colon/colon_tube.hpp"

namespace scopekin::model {

/// Poisson's ratio of colon tissue: nearly incompressible soft tissue (stated assumption), used
/// only for the shear modulus G = E / (2 (1 + nu)) of the hollow beam.
inline constexpr double kColonPoissonRatio = 0.49;
/// Shear correction of a thin-walled circular tube (Cowper 1966: ~0.5).
inline constexpr double kThinTubeShearCorrection = 0.5;

/// Hollow circular section: inner radius r, wall t, Young's modulus E [kPa]; stiffness only.
BeamSection hollow_colon_section(double inner_radius_mm, double wall_thickness_mm,
                                 double young_modulus_kPa);

struct ColonStructure {
    ScopeBeam beam;                     ///< one node per centerline point
    std::vector<NodeSupport> supports;  ///< clamps of the fixed regions
    BeamLoads loads;                    ///< the mesentery springs (no gravity: the tube is carried)
    std::vector<bool> mobile;           ///< per node: hangs on a mesentery
};

/// Builds the colon structure; `properties` per region, in kColonRegionsInOrder order.
ColonStructure build_colon_structure(const ColonTube& tube,
                                     const std::array<ColonRegionProperties, 8>& properties);
std::array<ColonRegionProperties, 8> default_colon_properties();

}  // namespace scopekin::model
