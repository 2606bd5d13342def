#pragma once
// A run folder read into the data the browser view shows (host_sim/view/README.md, "The page's
// data"): the colon at rest and the shapes over time, the handle's and the box's series beside
// the truth's, the box's alarms and fault flags as intervals, the truth's episodes.
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace scopekin::view {

/// A folder that cannot be viewed: says which file, which line and why (exit status 2).
struct ViewDataError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// The timeline's series keep at most this many points (every k-th box period); the alarms and
/// fault intervals are taken from every period.
inline constexpr std::size_t kMaxSeriesPoints = 8000;

/// Reads a run folder written by `scopekin simulate`, `scopekin demo` or one case of `scopekin
/// evaluate`: summary.json, truth.csv, firmware.csv, recording.csv (as the scorecard reads them),
/// snapshots.json and, where the run wrote it, frames.jsonl (the shapes over time; without it the
/// snapshots' few key moments are the frames). Throws ViewDataError.
nlohmann::json read_run_view(const std::filesystem::path& folder,
                             std::size_t max_series_points = kMaxSeriesPoints);

/// An evaluation's cases keep this many timeline points each (the page embeds them all; a case's
/// own folder, viewed alone, has kMaxSeriesPoints).
inline constexpr std::size_t kEvaluationCaseSeriesPoints = 2000;

/// True if `folder` holds an evaluation (`scopekin evaluate`: scorecard.json and cases/).
bool is_evaluation_folder(const std::filesystem::path& folder);

/// An evaluation folder (`scopekin evaluate`, unsharded or merged): its scorecard.json (kind
/// "evaluation") and each scored case's run as read_run_view reads it (case_views, with
/// kEvaluationCaseSeriesPoints); a case that cannot be read is listed in case_errors with why.
/// `progress(k, n, name)` is called before each case. Throws ViewDataError (no scorecard.json,
/// or one that is not JSON).
nlohmann::json read_evaluation_view(
    const std::filesystem::path& folder,
    const std::function<void(std::size_t, std::size_t, const std::string&)>& progress);

/// True if `folder` holds a discrepancy report (`scopekin discrepancy`: report.json, series.csv).
bool is_discrepancy_folder(const std::filesystem::path& folder);

/// A discrepancy report (kind "discrepancy"): report.json as it is, and series.csv grouped by
/// output and component (time_s, held_out, measured, before, after; at most kMaxSeriesPoints
/// each). Throws ViewDataError naming the file and line.
nlohmann::json read_discrepancy_view(const std::filesystem::path& folder);

}  // namespace scopekin::view
