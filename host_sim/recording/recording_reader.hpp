#pragma once
// Reading a recording CSV strictly (host_sim/recording/RECORDING.md).  Every problem that makes
// the file unusable is a RecordingError naming the 1-based line (and the column where there is
// one), quoting a cell or a column name with at most 80 characters; problems a command can live
// with are findings: gaps in the handle signals.  A time step between two rows longer than
// max_gap_s is refused: a command would step the box (or the model) across all of it.
#include <cstddef>
#include <istream>
#include <string>
#include <vector>

#include "host_sim/recording/recording_row.hpp"

namespace scopekin::recording {

/// A stretch of time in which a handle signal delivered nothing: from the last sample before it
/// (or the first row's time) to the next sample (or the last row's time).
struct RecordingGap {
    double start_s = 0;
    double end_s = 0;
    std::string signal;  ///< "handle_force_torque" or "insertion_roll"
    [[nodiscard]] double duration_s() const { return end_s - start_s; }
    friend bool operator==(const RecordingGap&, const RecordingGap&) = default;
};

/// Gaps longer than `threshold_s` (strictly) in the handle force/torque and the insertion/roll
/// signals, in time order per signal (force/torque first).  A signal that never delivered gives
/// one gap over the whole recording (if it is longer than the threshold).  No rows: no gaps.
std::vector<RecordingGap> find_gaps(const std::vector<RecordingRow>& rows, double threshold_s);

struct Recording {
    std::vector<RecordingRow> rows;
    std::vector<std::size_t> row_lines;                 ///< the line each row came from
    std::vector<std::string> extra_columns;             ///< the x_ columns, in file order
    std::vector<std::vector<std::string>> extra_cells;  ///< per row, one cell per extra column
    std::vector<RecordingGap> gaps;  ///< findings (RecordingReaderOptions::gap_threshold_s)
};

/// The longest time between two rows a reader accepts by default [s].
inline constexpr double kDefaultMaxGap_s = 60.0;

struct RecordingReaderOptions {
    double gap_threshold_s = 0.05;        ///< a handle signal silent for longer than this is a gap
    double max_gap_s = kDefaultMaxGap_s;  ///< two rows further apart than this: refused
};

class RecordingReader {
public:
    explicit RecordingReader(RecordingReaderOptions options = {});

    /// Reads a file; errors are prefixed with the file name ("run.csv: line 3, column ...").
    [[nodiscard]] Recording read_file(const std::string& path) const;
    /// Reads a stream; `source` (if not empty) prefixes every error message.
    [[nodiscard]] Recording read(std::istream& in, const std::string& source = "") const;

private:
    RecordingReaderOptions options_;
};

}  // namespace scopekin::recording
