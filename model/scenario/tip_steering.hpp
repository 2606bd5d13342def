#pragma once
// The physician's tip steering: with the angulation wheels the physician bends the scope's
// distal bending section so that the tip points down the lumen seen on the video. Modelled as a
// couple on the bending section: moments +M b at the tip node and -M b at the node
// `bending_section_mm` behind it (no net force), with
//   b = (a x d) / |a x d|   (a: the tip's axis, d: the direction from the tip to the centerline
//                            point `lookahead_mm` further along the colon than the tip's)
//   M = gain * EI * min(theta, theta_max) / L_bend   [N mm],  theta = angle(a, d) [rad]
// i.e. the moment that bends a section of length L_bend through theta (Euler-Bernoulli,
// curvature M / EI), scaled by a gain < 1 (a hand does not correct all at once; 0.5 is stable at
// h = 5-10 ms). theta_max = 180 deg: the CF-Q160L's up/down angulation (Olympus data sheet).
// The moments are recomputed from the state at the start of each step and held over it.
//
// Or, with `holds_curvature`, as the wheels do it: the wires bend the section to a commanded
// curvature and hold it there, stiffly. The section's elements are then bent at rest
// (WorldEffect::add_rest_curvature, implicit in the step) to
//   kappa = gain * min(theta0, theta_max) / L_bend  about  b0 = (a0 x d) / |a0 x d|
// with a0 the scope's axis at the section's base: a section of length L_bend bent uniformly
// through theta0 points its tip along d. The command depends on the base, not on the tip's own
// axis, so it does not chase the tip's answer; the hand turns the wheels towards it at no more
// than kWheelRate_rad_per_s (the section's angle), and lets them go back as fast when it stops
// steering.
// The firmware never sees the steering: it is what the hand does at the wheels, not at the shaft.
#include <Eigen/Dense>
#include <cmath>
#include <memory>
#include <vector>

#include "model/colon/colon_tube.hpp"
#include "model/scenario/hand_command_source.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model {

struct SteeringWindow {
    double start_s = 0;
    double end_s = 0;
    double lookahead_mm = 40.0;
    double bending_section_mm =
        80.0;  ///< CF-Q160L bending section (stated guess from its data sheet class: 7-10 cm)
    double gain = 0.5;
    /// Aim: false, at the centerline point lookahead_mm ahead (d above); true, along the turn:
    /// d = the mean of that direction and the centerline's direction at that point, so that in a
    /// tight flexure the section bends through the turn (about its angle) rather than towards a
    /// point on the turn's outer wall (stated guess: an endoscopist angulates until the lumen
    /// beyond the flexure is in view).
    bool follows_turn = false;
    /// The law: false, a couple from the tip's own axis (above); true, the wheels' commanded
    /// curvature held by the wires (above).
    bool holds_curvature = false;
};

/// How fast a hand turns the angulation wheels, as the section's angle [rad/s] (stated guess:
/// the big wheel's full 180 deg of up-angulation in about a second).
inline constexpr double kWheelRate_rad_per_s = M_PI;

class TipSteering final : public WorldEffect {
public:
    /// `colon` in the body frame (the scenario's), `bending_stiffness_Nmm2` the scope's EI,
    /// `element_mm` the scope's element length. Throws ModelError for a bad window.
    TipSteering(std::vector<SteeringWindow> windows, const ColonTube& colon,
                double bending_stiffness_Nmm2, double element_mm);
    /// Switched by a source instead (a physician scenario): steers while `control->steering`,
    /// with its lookahead, bending section and gain (read at every step).
    TipSteering(std::shared_ptr<const SceneControl> control, const ColonTube& colon,
                double bending_stiffness_Nmm2, double element_mm);
    std::string name() const override { return "tip_steering"; }
    void add_scope_loads(const WorldEffectView& view, std::vector<NodalLoad>& loads) const override;
    void add_rest_curvature(const WorldEffectView& view,
                            std::vector<Eigen::Vector3d>& curvature_per_mm) const override;

private:
    /// The window steering at the view's time (`switched` holds a control's), or nullptr.
    const SteeringWindow* active_window(const WorldEffectView& view,
                                        SteeringWindow& switched) const;
    /// Follows the tip along the centerline (once per step).
    void track_tip(const WorldEffectView& view) const;
    /// Where the physician wants the tip to point, from the tip (unit, body frame).
    Eigen::Vector3d wanted_direction(const WorldEffectView& view,
                                     const SteeringWindow& window) const;
    /// The bending section's length in elements, at least 1.
    std::size_t section_elements(const SteeringWindow& window) const;

    std::vector<SteeringWindow> windows_;
    std::shared_ptr<const SceneControl> control_;
    ColonTube colon_;
    double ei_Nmm2_;
    double element_mm_;
    mutable double tip_path_mm_ =
        -1;  // the tip's place along the colon at the last call (tracking)
    mutable double tracked_at_s_ = -1;  // the step the tracking is of
    // The wheels' state (holds_curvature): the curvature the wires hold [1/mm, body frame] and
    // over how many elements behind the tip.
    mutable Eigen::Vector3d held_curvature_per_mm_ = Eigen::Vector3d::Zero();
    mutable std::size_t held_elements_ = 0;
    mutable double turned_at_s_ = -1;  // the step the wheels last turned in, and from where
    mutable Eigen::Vector3d turned_from_per_mm_ = Eigen::Vector3d::Zero();
};

}  // namespace scopekin::model
