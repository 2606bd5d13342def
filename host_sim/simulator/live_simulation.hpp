#pragma once
// A live simulation: the world (full-order model + truth effects, stepped by the scenario's
// procedure) read by the sensor models every 1 ms, the rows they deliver written to the
// recording and fed to the unmodified firmware (FirmwareLoop) as they arrive. Simulated time is
// the world's; the run is deterministic for a given seed.
#include <cstdint>
#include <functional>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/sensors/sensor_suite.hpp"
#include "host_sim/simulator/box_observer.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"

namespace scopekin::host_sim {

/// One world step as the live view takes it (`scopekin simulate --view`, host_sim/view/README.md):
/// the timeline's values now, and the shapes, built only if asked for.
struct LiveViewStep {
    double time_s = 0;
    /// time_s, handle, insertion, true and box tip, forces, alarms (built only if asked for)
    std::function<nlohmann::ordered_json()> row;
    std::function<std::string()> frame;  ///< a frames.jsonl line (JSON text)
};

/// What the handle reads (the live view's handle columns).
struct HandleReading {
    double force_N = 0;
    double torque_Nmm = 0;
    double insertion_mm = 0;
};

/// The live view's row of the box alone (no truth): the time, the handle, the box's outputs
/// (tip, SD, largest force, alarms, fault flags, stations: path and normal force).
nlohmann::ordered_json box_view_row(double time_s, const HandleReading& handle,
                                    const kinetics::Outputs& box);

struct LiveStreams {
    std::ostream* recording = nullptr;  ///< recording.csv (sensor rows)
    std::ostream* world = nullptr;      ///< world.csv (true state at the output rate)
    std::ostream* firmware = nullptr;   ///< firmware.csv (the box's outputs per period)
    std::ostream* contacts =
        nullptr;  ///< contacts.csv (loaded contacts at the output rate), optional
    std::ostream* truth =
        nullptr;  ///< truth.csv (what the box estimates, true, per box period), optional
    std::ostream* procedure =
        nullptr;  ///< procedure.csv (what the hand did, at the output rate), optional
    /// frames.jsonl (the shapes `scopekin view` replays: one JSON line per frame, at most every
    /// frames_period_s), optional
    std::ostream* frames = nullptr;
    double frames_period_s = 0.1;
    /// Called after every world step (the live view), optional.
    std::function<void(const LiveViewStep&)> view_step;
};

/// Advance efficiency of the true tip per region: tip advance / handle advance while the hand
/// advances, the tip's region deciding the bucket.
struct RegionAdvance {
    double handle_advance_mm = 0;
    double tip_advance_mm = 0;
};

struct LiveResult {
    model::SimulationSummary world;
    BoxObservation box;
    nlohmann::ordered_json box_json;
    nlohmann::ordered_json box_section;  ///< the box's own faults and counters (summary "box")
    nlohmann::ordered_json snapshots;    ///< {"colon": ..., "snapshots": [...]}
    std::map<std::string, RegionAdvance> advance_by_region;  ///< region name -> sums
    double peak_measured_handle_force_N = 0;
    double peak_true_tip_contact_force_N = 0;
    double peak_true_contact_force_N = 0;
    std::string peak_true_contact_region;
    double final_tip_path_mm = 0;
    std::string final_tip_region;
    std::uint64_t rows_delivered = 0;
    std::uint64_t firmware_periods = 0;
    nlohmann::ordered_json sensor_counters;
    nlohmann::ordered_json truth;  ///< summary "truth": definitions, loop and force episodes
    double wall_time_s = 0;
};

/// Runs `scenario` (a world scenario) live. `on_progress` sees every world step.
LiveResult run_live(const model::Scenario& scenario, const sensors::SensorSuiteConfig& sensors,
                    std::uint64_t seed, const LiveStreams& streams,
                    const std::function<void(const model::SimulationProgress&)>& on_progress);

/// The colon region a path position [mm] falls in.
std::string region_at_path(const model::ColonTube& colon, double path_mm);

}  // namespace scopekin::host_sim
