#pragma once
// Where "truth" effects enter the world (the discrepancy workflow hides them in synthetic
// recordings and must later name them). An effect may change parameters once, when the world
// is built, add loads on the scope every step, change the friction of each contact and the
// wall's local compliance at each contact, and bend scope elements at rest. The library of effects is model/effects/
// (model/effects/EFFECTS.md).
// The default of every hook is "no change", so an effect overrides only what it touches.
// All vectors are in the colon's (body) frame, in mm and N.
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/beam/beam_loads.hpp"
#include "model/beam/beam_section.hpp"
#include "model/colon/colon_region.hpp"
#include "model/colon/colon_tube.hpp"

namespace scopekin::model {

/// What an effect may read about the world during a step. Scope quantities are those at the
/// start of the step (the loads an effect adds are applied at its end: an explicit coupling, but
/// for a load that states its stiffness, NodalLoad::stiffness_N_per_mm, which the step takes
/// implicitly).
struct WorldEffectView {
    double time_s = 0;  ///< at the end of the step being computed
    double time_step_s = 0;
    double insertion_depth_mm = 0;  ///< at the start of the step
    double scope_radius_mm = 0;
    std::vector<Eigen::Vector3d> scope_nodes_mm;  ///< body frame, node 0 = handle, last = tip
    std::vector<double> arc_from_tip_mm;          ///< per scope node
    std::vector<Eigen::Vector3d> scope_velocities_mm_per_s;  ///< per scope node, body frame
    std::vector<Eigen::Vector3d>
        scope_axes;  ///< unit tangent per scope node (handle -> tip), body frame
    /// Per scope node: held on the entry axis by the hand this step (outside the body). Loads on
    /// held nodes do not act on the scope (the hand takes them), so effects leave them out.
    std::vector<bool> scope_node_held;
    /// The colon's centerline and lumen radii at rest, body frame (nullptr when unknown).
    const ColonTube* colon_at_rest = nullptr;
};

/// One contact as the friction hook sees it.
struct ContactFrictionView {
    double arc_from_tip_mm = 0;
    ColonRegion region = ColonRegion::rectum;
    double mu = 0;  ///< the coefficient so far (scenario value, zones, earlier effects)
    /// |tangential velocity of the scope node relative to the wall| at the start of the step
    /// [mm/s]: the node's velocity minus the colon's at the contact point (both over the last
    /// step), its component along the wall normal removed.
    double sliding_speed_mm_per_s = 0;
};

/// One contact as the wall-compliance hook sees it.
struct ContactWallView {
    double arc_from_tip_mm = 0;
    ColonRegion region = ColonRegion::rectum;
    double previous_normal_force_N =
        0;  ///< this scope node's contact force at the previous step (0 if none)
    double base_compliance_mm_per_N =
        0;  ///< the compliance so far (scenario value, earlier effects)
};

class WorldEffect {
public:
    virtual ~WorldEffect() = default;
    virtual std::string name() const = 0;
    /// The effect's parameters, keys with their units (e.g. {"factor": 0.85}); what outputs report.
    virtual nlohmann::json parameters() const { return nlohmann::json::object(); }
    /// Parameter changes, once at construction: the scope's element sections (node 0 = handle side
    /// first; the elements are of equal length, scope_length_mm / sections.size()).
    virtual void adjust_scope_sections(std::vector<BeamSection>& /*sections*/,
                                       double /*scope_length_mm*/) const {}
    /// Parameter changes, once at construction: the colon's region properties.
    virtual void adjust_colon_properties(
        std::array<ColonRegionProperties, 8>& /*properties*/) const {}
    /// Extra loads on scope nodes at the end of the step (body frame) [N, N mm].
    virtual void add_scope_loads(const WorldEffectView& /*view*/,
                                 std::vector<NodalLoad>& /*loads*/) const {}
    /// Rest curvature of scope elements, held over the step and implicit in it (body frame, 1/mm:
    /// the bending axis times the curvature; element e joins nodes e and e + 1; zero = straight):
    /// the bending section angulated by its wires (model/scenario/tip_steering.hpp). Added to
    /// what earlier effects set.
    virtual void add_rest_curvature(const WorldEffectView& /*view*/,
                                    std::vector<Eigen::Vector3d>& /*curvature_per_mm*/) const {}
    /// Friction coefficient of one contact. The default calls the older form below, so an effect
    /// that only needs position and region may override that one.
    virtual double friction_coefficient(const ContactFrictionView& contact) const {
        return friction_coefficient(contact.arc_from_tip_mm, contact.region, contact.mu);
    }
    /// Friction coefficient of one contact without its sliding speed; `mu` is the value so far.
    virtual double friction_coefficient(double /*arc_from_tip_mm*/, ColonRegion /*region*/,
                                        double mu) const {
        return mu;
    }
    /// Local compliance of the wall at one contact [mm/N], added to the contact's diagonal block
    /// of the Delassus operator (the wall's own indentation: delta = c f).
    virtual double wall_compliance_mm_per_N(const ContactWallView& contact) const {
        return contact.base_compliance_mm_per_N;
    }
};

}  // namespace scopekin::model
