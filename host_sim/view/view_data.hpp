#pragma once
// A run folder read into the data the browser view shows (host_sim/view/README.md, "The page's
// data"): the colon at rest and the shapes over time, the handle's and the box's series beside
// the truth's, the box's alarms and fault flags as intervals, the truth's episodes.
#include <filesystem>
#include <stdexcept>

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
nlohmann::json read_run_view(const std::filesystem::path& folder);

}  // namespace scopekin::view
