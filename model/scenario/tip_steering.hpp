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
// The firmware never sees the steering: it is what the hand does at the wheels, not at the shaft.
#include <Eigen/Dense>
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
};

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

private:
    std::vector<SteeringWindow> windows_;
    std::shared_ptr<const SceneControl> control_;
    ColonTube colon_;
    double ei_Nmm2_;
    double element_mm_;
    mutable double tip_path_mm_ =
        -1;  // the tip's place along the colon at the last call (tracking)
};

}  // namespace scopekin::model
