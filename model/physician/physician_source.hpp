#pragma once
// The physician (physician.hpp) connected to a simulated World: each step it reads the world
// through its public API only — what a physician sees on the video and feels at the handle
// (WorldObserver) — lets the Physician decide, and writes the decision into the run's
// SceneControl (tip steering, the assistant's abdominal pressure) before returning the hand's
// command. It never reads the box's (firmware's) outputs.
#include <memory>
#include <vector>

#include "model/physician/physician.hpp"
#include "model/scenario/hand_command_source.hpp"
#include "model/world/world.hpp"

namespace scopekin::model {

/// What a physician sees and feels of a World. The tip's place along the colon is the colon
/// coordinate of model/truth (the closest point of the displaced centerline, as its arc at
/// rest: the mucosa the tip faces), tracked from step to step: searched within
/// kMaxTipSpeed_mm_per_s x the time since the last look (at least kMinTrackWindow_mm) of its last
/// place. So it never jumps to another turn of a loop or a neighbouring lumen, follows a colon
/// that shortens over the scope, and does not believe a tip that teleports (a world whose scope
/// has gone unstable moves the tip hundreds of mm in one step).
class WorldObserver {
public:
    explicit WorldObserver(const World& world);
    PhysicianObservation observe(const World& world);

    /// 1 m/s: 25 times the fastest hand (a loop giving back its slack moves the tip at tens of
    /// mm/s); 10 mm per 10 ms step.
    static constexpr double kMaxTipSpeed_mm_per_s = 1000.0;
    static constexpr double kMinTrackWindow_mm = 5.0;
    /// The first look: around the insertion depth.
    static constexpr double kFirstTrackWindow_mm = 60.0;

private:
    std::vector<double> rest_arc_mm_;
    double tip_path_mm_ = -1;
    double last_time_s_ = 0;
};

class PhysicianSource final : public HandCommandSource {
public:
    /// `control` is the SceneControl the scenario's switched effects read (Scenario::scene_control);
    /// it is reset here. `world` must outlive the source.
    PhysicianSource(const World& world, const PhysicianSpec& spec,
                    std::shared_ptr<SceneControl> control);

    HandleCommand command_for_step(std::size_t step, double t_s, double h_s, double depth_now_mm,
                                   double roll_now_rad) override;
    std::vector<std::string> warnings() const override;
    bool finished() const override { return physician_.finished(); }
    HandState hand_state() const override { return state_; }
    ProcedureOutcome outcome() const override { return physician_.outcome(); }
    const Physician& physician() const { return physician_; }

private:
    const World& world_;
    WorldObserver observer_;
    Physician physician_;
    std::shared_ptr<SceneControl> control_;
    HandState state_;
};

}  // namespace scopekin::model
