#pragma once
// Running a world scenario: builds the World, plays the procedure step by step until its end,
// samples the state at the output rate and sums up the run. Independent of the command line:
// samples and progress go to callbacks. The stepping loop is the same whoever commands the
// hand (hand_command_source.hpp): the procedure, or a recording's encoder.
#include <Eigen/Dense>
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "model/scenario/hand_command_source.hpp"
#include "model/scenario/scenario.hpp"
#include "model/world/world.hpp"

namespace scopekin::model {

/// A run is stopped as no longer physical beyond these (ModelError-free failures).
inline constexpr double kMaxPhysicalContactForce_N = 1000.0;
inline constexpr double kMaxPhysicalPenetration_mm = 1.0;

/// One row of world.csv: the world's true state after a step (or the initial state).
struct WorldRow {
    double time_s = 0;
    double handle_force_N = 0;
    double handle_torque_Nmm = 0;
    double insertion_depth_mm = 0;
    double roll_deg = 0;
    Eigen::Vector3d tip_mm = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d>
        nodes_mm;                      ///< at Scenario::outputs.nodes_from_tip_mm (nearest node)
    std::size_t contact_count = 0;     ///< contacts carrying load (normal force > 0)
    double contact_force_total_N = 0;  ///< sum of normal forces
    double contact_force_max_N = 0;
    std::array<double, 8> max_contact_force_by_region_N{};  ///< kColonRegionsInOrder order
    std::size_t sticking_contacts = 0;
    std::size_t slipping_contacts = 0;
    bool has_tip_driving_angle = false;
    double tip_driving_angle_deg = 0;  ///< of the distal-most loaded contact
    std::size_t gs_sweeps = 0;         ///< of the step that led here (0 at t = 0)
    /// |net force| the assistant's hand passes to the scope through the abdomen [N]
    /// (World::effect_force_N("abdominal_pressure"); 0 while nobody presses).
    double assistant_pressure_force_N = 0;
};

struct SimulationProgress {
    double time_s = 0;
    double end_s = 0;
    std::size_t contacts = 0;  ///< loaded contacts now
    double handle_force_N = 0;
};

/// One mobile stretch's telescoping over a run (summary.json world.telescoping).
struct StretchPleating {
    ColonRegion region = ColonRegion::sigmoid;  ///< of the stretch's first mobile node
    double rest_length_mm = 0;                  ///< unpleated, fixed end to fixed end
    double max_fraction = 0;                    ///< p_max (capped by the chord)
    double peak_fraction = 0;                   ///< largest p reached
    double final_fraction = 0;                  ///< p at the end
};

struct SimulationSummary {
    bool complete = false;
    std::string message;        ///< why the run failed (empty when complete)
    double failure_time_s = 0;  ///< end time of the step that failed
    std::size_t steps = 0;      ///< steps taken successfully
    std::size_t samples = 0;
    double end_time_s = 0;        ///< where the procedure ends
    double simulated_time_s = 0;  ///< world time reached
    double wall_time_s = 0;
    double real_time_factor = 0;                ///< simulated / wall time
    double max_handle_force_N = 0;              ///< largest |handle force|
    double max_handle_torque_Nmm = 0;           ///< largest |handle torque|
    double max_assistant_pressure_force_N = 0;  ///< largest WorldRow::assistant_pressure_force_N
    double assistant_pressing_s = 0;  ///< time with an assistant's force on the scope (> 0.1 N)
    double assistant_pressure_impulse_Ns = 0;  ///< its integral over that time
    double max_contact_force_N = 0;
    std::array<double, 8> max_contact_force_by_region_N{};
    std::size_t max_simultaneous_contacts = 0;  ///< loaded contacts
    double gs_sweeps_mean = 0;
    std::size_t gs_sweeps_max = 0;
    std::size_t dropped_contacts_total = 0;
    std::size_t material_tangent_fallbacks = 0;
    std::size_t under_relaxed_steps = 0;  ///< steps whose contact solve cycled (World::step)
    /// Per mobile stretch, in order from the anus (all p = 0 when telescoping is off).
    std::vector<StretchPleating> telescoping;
    double max_penetration_mm = 0;
    double friction_work_Nmm = 0;  ///< sum over steps and contacts of f_T . slip (<= 0: dissipated)
    Eigen::Vector3d final_tip_mm = Eigen::Vector3d::Zero();
    double final_insertion_depth_mm = 0;
    double final_roll_deg = 0;
    std::vector<std::string> warnings;
    /// How the procedure went (summary.json "procedure"): the source's outcome, with
    /// duration_s the world time reached and end_reason "failed_step" for a failed run.
    ProcedureOutcome procedure;
};

struct SimulationCallbacks {
    /// Called at t = 0 and at the first step at or after each sample time k / sample_rate_Hz.
    std::function<void(const WorldRow&, const World&)> on_sample;
    /// Called after every step.
    std::function<void(const SimulationProgress&)> on_progress;
    /// Called after every successful step with the world (before on_sample / on_progress); the
    /// host simulator runs its sensors and the firmware here.
    std::function<void(const World&, const WorldStepReport&)> on_step;
    /// Called with every sample (after on_sample): the hand's state at the command that led
    /// there (procedure.csv).
    std::function<void(double time_s, const HandState&)> on_hand_sample;
};

/// Builds the world of a world scenario. Throws ModelError (naming the scenario file) if the
/// world cannot be built (e.g. the initial insertion crosses the wall).
std::unique_ptr<World> build_world(const Scenario& scenario);

/// The world.csv row of the world's current state; `last_step` is the step that led there
/// (nullptr at t = 0). `output_nodes`: scope node indices of the extra node columns.
WorldRow sample_world(const World& world, const WorldStepReport* last_step,
                      const std::vector<std::size_t>& output_nodes);

/// Scope node indices of Scenario::outputs.nodes_from_tip_mm.
std::vector<std::size_t> output_nodes(const Scenario& scenario);

/// The steps a run takes: from the world's step now to `last_step`.
struct SimulationSpan {
    std::size_t first_step =
        0;  ///< the world's step now: 0 fresh from build_world, else a restored state's
    std::size_t last_step = 0;
    double end_s = 0;  ///< world time at last_step (SimulationSummary::end_time_s, progress)
};

/// The stepping loop: steps `world` through `span` with the commands of `hand`, until the end,
/// the source finishing (HandCommandSource::finished: the run then ends where it is) or the first
/// failed or unphysical step. `scenario` gives the samples' rate and node columns.
SimulationSummary run_simulation(World& world, const Scenario& scenario, HandCommandSource& hand,
                                 const SimulationSpan& span, const SimulationCallbacks& callbacks);

/// Plays the scenario's procedure on `world` (fresh from build_world) until its end or the first
/// failed or unphysical step; or, with a "physician", lets the physician (model/physician/) drive
/// until the cecum is reached, it gives up, or physician.max_duration_s. Either way the tip's
/// arrival at the cecum is watched (ProcedureOutcome; kCecumReach_mm).
SimulationSummary run_simulation(World& world, const Scenario& scenario,
                                 const SimulationCallbacks& callbacks);

}  // namespace scopekin::model
