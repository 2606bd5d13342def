#pragma once
// One evaluated case's run folder, read back for scoring (host_sim/evaluate/README.md, "What a
// case is scored on"): the truth at the box's periods (truth.csv and summary.json "truth"), the
// box's outputs (firmware.csv), the handle sensors as the box received them (recording.csv) and
// the procedure's outcome (summary.json "procedure", written by physician runs).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/evaluate/scoring.hpp"

namespace scopekin::evaluate {

/// A run folder that cannot be scored (a file missing or malformed): names the file and line.
struct CaseDataError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// The box's period [s] (host_sim::kBoxPeriodUs).
inline constexpr double kPeriod_s = 0.005;

/// What a physician run reports (summary.json "procedure"; the physicians' contract): absent
/// for runs that do not write it.
struct ProcedureOutcome {
    bool known = false;  ///< the summary has a "procedure" section
    std::string kind;    ///< "physician" or "scripted"
    std::string style;   ///< physician runs
    std::optional<bool> cecum_reached;
    std::optional<double> cecum_time_s;
    std::optional<double> insertion_at_cecum_mm;
};

/// The truth and the box's outputs at each period, joined row by row (the same time_s text).
struct CaseRun {
    std::string status;          ///< summary.json "status": "complete" or "failed"
    std::string message;         ///< summary.json "message"
    double duration_s = 0;       ///< simulated
    double wall_time_s = 0;      ///< of the simulation
    std::vector<double> time_s;  ///< period release times
    // truth.csv
    std::vector<double> true_tip_path_mm;
    std::vector<double> true_max_station_force_N;
    std::vector<double> insertion_mm;  ///< true insertion
    // summary.json "truth"
    std::vector<Episode> loop_episodes, warning_episodes, critical_episodes;
    /// When the scope went through the colon wall (the first period whose truth.csv
    /// scope_beyond_wall_mm exceeds TruthReader::kThroughWall_mm): the run is not physical from
    /// there on, so every series ends before it and episodes that began later are dropped (an
    /// episode still up then is up at the end). Unset: the whole run.
    std::optional<double> scope_through_wall_s;
    // firmware.csv: the box's outputs
    std::vector<double> box_tip_path_mm;  ///< the published tip (the tip observer's)
    /// The reduced model's tip (column model_tip_path_mm); runs written before the tip observer
    /// lack the column, and their published tip was the model's.
    std::vector<double> box_model_tip_path_mm;
    std::vector<double> box_tip_uncertainty_mm;  ///< one SD; empty for runs before the observer
    std::vector<double> box_max_contact_force_N;
    /// The reduced model's largest force (column model_max_contact_force_N); runs written before
    /// the contact force trees lack the column, and their published force was the model's.
    std::vector<double> box_model_max_contact_force_N;
    std::vector<std::uint8_t> box_self_lock;
    /// The reduced model's self-lock alarm (column model_self_lock_alarm); runs written before
    /// the loop alarm from evidence lack it, and their published alarm was the model's.
    std::vector<std::uint8_t> box_model_self_lock;
    std::vector<std::uint8_t> box_contact_level;
    /// The reduced model's contact-force level (column model_contact_force_level); runs written
    /// before the level from evidence (2026-11-30) lack it, and their published level was the
    /// model's.
    std::vector<std::uint8_t> box_model_contact_level;
    std::vector<std::uint32_t> box_fault_flags;
    // recording.csv: the handle force and insertion the box received, at each period (the last
    // sample at or before the period's time; NaN before the first)
    std::vector<double> handle_force_N;
    std::vector<double> handle_torque_Nmm;
    std::vector<double> handle_insertion_mm;
    /// The same, at every sensor sample (1 kHz): what the handle force monitor filters.
    std::vector<double> sample_time_s, sample_force_N, sample_insertion_mm;
    ProcedureOutcome procedure;
};

/// Reads a run folder written by `scopekin simulate`: summary.json, truth.csv, firmware.csv,
/// recording.csv, cut where the scope went through the colon wall (scope_through_wall_s).
/// Throws CaseDataError (a missing file, a missing column, rows that do not join, a cell that
/// is not a number), naming the file and line.
CaseRun read_case_run(const std::filesystem::path& folder);

/// The named columns of a CSV file without quoted cells (firmware.csv, truth.csv) as numbers, one
/// vector per name (an empty cell is NaN). Throws CaseDataError naming the file, line and column
/// (a missing file or column, a row of another width, a cell that is not a number).
std::vector<std::vector<double>> read_number_columns(const std::filesystem::path& file,
                                                     const std::vector<std::string>& names);

/// summary.json "procedure" (physicians' contract), or unknown.
ProcedureOutcome read_procedure(const nlohmann::json& summary);

/// A truth episode list (summary.json "truth": loop_episodes, or force_episodes' lists):
/// onset_s, end_s (null: up at the end), and for loops "type" and "region".
std::vector<Episode> read_episodes(const nlohmann::json& list, const std::string& where);

}  // namespace scopekin::evaluate
