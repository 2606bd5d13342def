#pragma once
// The assistant's abdominal pressure: with a flat hand on the abdomen over a mobile stretch of
// colon (sigmoid, transverse) the assistant keeps it from bowing out while the physician pushes,
// so the shaft cannot re-loop there (Cotton & Williams, Practical Gastrointestinal Endoscopy,
// 7th ed. 2014, ch. 7, "specific abdominal pressure"). Modelled as the colon wall pressed back
// to its place: on each inserted scope node whose closest point of the colon at rest lies in one
// of the pressed regions,
//   excess = max(0, d - (R - r)),  d = distance of the node from the rest centerline,
//            R = lumen radius there, r = scope radius (how far the node pushes the wall out),
//   F = -k l excess u           [N], u = unit vector from the rest centerline to the node,
// with l the scope length the node carries [mm] and k [N/mm per mm of scope] the firmness of
// the hand (a stated guess: 0.02 N/mm^2 holds a bowing 10 mm node with 2 N, ten times the
// mesentery of model/effects/EFFECTS.md 2). The force's stiffness k l u u^T goes with it
// (NodalLoad::stiffness_N_per_mm): the world's step takes the push implicitly, so a firm hand is
// stable at any step. The hand presses in over `ramp_s` (k rises linearly
// from 0): a firm hand switched on within one step jolts the stiff shaft. The same law as the truth effect
// mesenteric_retraction, but switched on in time windows and over chosen regions: it is what
// the assistant does, not a property of the patient. The firmware never sees it.
//
// A hand that gives way (a physician's assistant, SceneControl): a spring without a limit answers
// a loop that has already bowed far out with hundreds of newtons, more than a hand passes through
// the abdominal wall. Each region's hand gives at most SceneControl::pressure_max_force_N: where
// the net force on the region's nodes (their vector sum: what the hand must supply; forces that
// cancel are the abdomen's confinement) exceeds it, the region's forces and stiffnesses are
// scaled down by the same factor (the hand keeps its direction and yields in proportion). Scripted
// windows are the experimenter's spring and have no limit.
#include <memory>
#include <vector>

#include "model/colon/colon_region.hpp"
#include "model/colon/colon_tube.hpp"
#include "model/scenario/hand_command_source.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model {

struct AbdominalPressureWindow {
    double start_s = 0;
    double end_s = 0;
    std::vector<ColonRegion> regions{ColonRegion::sigmoid};
    double stiffness_N_per_mm2 = 0.02;  ///< k
    double ramp_s =
        1.0;  ///< time to press in [s], at most the window; 0 = at once (scenario default: 1 s or the window)
};

class AbdominalPressure final : public WorldEffect {
public:
    /// Throws ModelError for a bad window (names "abdominal_pressure[i].field").
    explicit AbdominalPressure(std::vector<AbdominalPressureWindow> windows);
    /// Switched by a source instead (a physician scenario): presses each region from
    /// `control->pressure_since_s[region]` on, k rising over its pressure_ramp_s (read at every
    /// step).
    explicit AbdominalPressure(std::shared_ptr<const SceneControl> control);
    std::string name() const override { return "abdominal_pressure"; }
    void add_scope_loads(const WorldEffectView& view, std::vector<NodalLoad>& loads) const override;

private:
    std::vector<AbdominalPressureWindow> windows_;
    std::shared_ptr<const SceneControl> control_;
};

}  // namespace scopekin::model
