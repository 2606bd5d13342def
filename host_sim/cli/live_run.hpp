#pragma once
// A live simulation written to a run folder (host_sim/README.md, "Commands"): recording.csv,
// world.csv, firmware.csv, snapshots.json and summary.json. Used by `simulate` (world
// scenarios) and `demo`. Files are written as NAME.part; a run that fails leaves
// NAME.incomplete.csv and a summary with status "failed". summary.json is renamed last of all,
// after `before_summary` (the demo's plots) has run.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "host_sim/simulator/live_simulation.hpp"
#include "model/scenario/scenario.hpp"

namespace scopekin::cli {

struct LiveRunOptions {
    std::filesystem::path out;
    std::uint64_t seed = 1;
    bool quiet = false;
    std::string command = "simulate";  ///< for messages
    /// Shapes for `scopekin view` (frames.jsonl) this many times per simulated second; 0: none.
    double frames_hz = 0;
    /// The live view (`simulate --view`): every world step, optional.
    std::function<void(const host_sim::LiveViewStep&)> view_step;
    /// Runs with every other file finished (complete: the run completed) and summary.json still
    /// summary.json.part (its path is given); summary.json is renamed after it returns.
    std::function<void(const std::filesystem::path& summary_part, bool complete)> before_summary;
};

struct LiveRunReport {
    host_sim::LiveResult result;
    nlohmann::ordered_json summary;
    bool complete = false;
};

/// Throws ModelError (bad scenario or sensor configuration: exit 2) or OutputError (exit 3).
LiveRunReport run_live_to_folder(const model::Scenario& scenario, const LiveRunOptions& options);

/// summary.json "procedure": how the procedure went (model/scenario/README.md, "Outputs").
nlohmann::ordered_json procedure_json(const model::ProcedureOutcome& outcome);

/// The alarm timeline and the summary table (stdout), as `demo` prints them.
void print_run_tables(const LiveRunReport& report);

/// One line per fault bit of the box (BoxFault, TrackerFault) a run saw, from summary.json "box":
/// when it was first set and in how many periods, as print_run_tables prints the estimator's.
void print_box_faults(const nlohmann::ordered_json& box);

}  // namespace scopekin::cli
