#pragma once
// Where a run's hand commands come from. run_simulation (simulation.hpp) is the one stepping loop
// for every world run; what the hand does at each step is asked of a source: the procedure's
// player (procedure.hpp) for a scripted scenario, the physician (model/physician/) who reacts to
// the world, or a recording's encoder for `scopekin discrepancy`
// (host_sim/discrepancy/model_run.hpp).
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "model/world/world.hpp"

namespace scopekin::model {

/// What the physician's hands do besides the handle, switched per step by a source that decides
/// it (the physician): tip steering with the angulation wheels (tip_steering.hpp) and the
/// assistant's abdominal pressure (abdominal_pressure.hpp). The effects built for a physician
/// scenario read it at every step instead of time windows; whoever holds it writes it before the
/// step it applies to.
struct SceneControl {
    bool steering = false;
    double steering_lookahead_mm = 40.0;
    double steering_bending_section_mm = 80.0;
    double steering_gain = 0.5;
    /// Aim along the turn: the tip is bent towards the mean of the direction to the centerline
    /// point ahead and the centerline's own direction there (tip_steering.hpp), so that it
    /// follows a tight flexure instead of pointing at its outer wall.
    bool steering_follows_turn = false;
    /// The wheels' law: the section's curvature commanded and held (tip_steering.hpp).
    bool steering_holds_curvature = false;
    /// Per region (kColonRegionsInOrder order): since when the assistant presses there [s], or
    /// empty while not pressing. Each region's firmness rises linearly over `pressure_ramp_s`
    /// from that time (a hand pressed in, as AbdominalPressureWindow::ramp_s).
    std::array<std::optional<double>, 8> pressure_since_s{};
    double pressure_stiffness_N_per_mm2 = 0.07;
    double pressure_ramp_s = 1.0;
    /// The most one hand gives over a region [N]: the region's net force (the vector sum over its
    /// nodes) is scaled down to it (abdominal_pressure.hpp, "A hand that gives way").
    double pressure_max_force_N = 50.0;

    bool pressing() const {
        for (const auto& since : pressure_since_s)
            if (since) return true;
        return false;
    }
};

/// The hand's state at a step: one row of procedure.csv (host_sim/README.md).
struct HandState {
    std::string state = "hold";  ///< what the hand does (e.g. advance, pause, reduce_loop)
    double speed_mm_per_s = 0;   ///< commanded insertion speed, + = in
    double roll_deg = 0;         ///< commanded roll
    bool steering = false;       ///< tip steering on
    bool pressure = false;       ///< the assistant presses on the abdomen
};

/// How a procedure went: summary.json "procedure" (model/scenario/README.md).
struct ProcedureOutcome {
    std::string kind = "scripted";  ///< "scripted" or "physician"
    std::string style;              ///< the physician's style ("" when scripted)
    std::uint64_t seed = 0;         ///< the physician's seed
    bool cecum_reached = false;
    std::optional<double> cecum_time_s;
    std::optional<double> insertion_at_cecum_mm;
    std::size_t loop_reductions = 0;
    double abdominal_pressure_s = 0;  ///< simulated time with pressure on (any region)
    double duration_s = 0;
    /// "cecum_reached", "max_duration", "gave_up", "end_of_procedure" (scripted) or "failed_step"
    std::string end_reason;
};

class HandCommandSource {
public:
    virtual ~HandCommandSource() = default;
    /// The command for world step `step` (the step that takes the world from step - 1 to step,
    /// from world time t_s to t_s + h_s). `depth_now_mm` and `roll_now_rad` are the world's at t_s.
    virtual HandleCommand command_for_step(std::size_t step, double t_s, double h_s,
                                           double depth_now_mm, double roll_now_rad) = 0;
    /// What the source noticed while playing (SimulationSummary::warnings).
    virtual std::vector<std::string> warnings() const { return {}; }
    /// True when the source ends the run before the span's end (the physician at the cecum, or
    /// giving up): run_simulation asks before every step.
    virtual bool finished() const { return false; }
    /// The hand's state at the last command (procedure.csv).
    virtual HandState hand_state() const { return {}; }
    /// How the procedure went so far (SimulationSummary::procedure); the end reason is filled in
    /// by run_simulation where the source leaves it empty.
    virtual ProcedureOutcome outcome() const { return {}; }
};

}  // namespace scopekin::model
