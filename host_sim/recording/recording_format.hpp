#pragma once
// The recording CSV: its columns, the plausible ranges, formatting a row and writing a file.
// The schema is documented in host_sim/recording/RECORDING.md.
//
// Formatting prints exactly what the wire carries: every value is first rounded to its wire
// resolution (wire_values.hpp), then printed from that integer with as many decimals as the
// resolution needs (handle force 3, torque 1, insertion 2, roll 4, positions 3, tip force 3;
// quaternion components 6, finer than the 1/16384 step; time 6 = µs).  Parsing a printed cell
// and encoding it again gives the same raw integer (tested exhaustively over the edge values).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "host_sim/recording/recording_row.hpp"

namespace scopekin::recording {

/// The 37 columns in the order the writer writes them (the reader takes any order).
const std::vector<std::string>& recording_columns();
/// The header line (no newline): the columns joined by commas.
std::string recording_header();

/// A text as one CSV cell on one line (the summaries of `batch` and `evaluate`): unchanged
/// unless it holds a comma, a quote or a line break; then in quotes, its quotes doubled and
/// its line breaks turned into spaces.
std::string csv_cell(std::string_view text);

/// Plausible ranges: a row outside them is rejected by the reader and refused by the writer.
/// The CAN signals' limits are the DBC's (the wire cannot carry more), the EM position and tip
/// force limits the serial receiver's defaults (em_tracker_serial.md §3).  A value is inside when
/// it is inside once rounded to its wire resolution (within half a step of the limit).
struct RecordingLimits {
    static constexpr double force_min_N = -163.84, force_max_N = 163.835;
    static constexpr double torque_min_Nmm = -3276.8, torque_max_Nmm = 3276.7;
    static constexpr double insertion_min_mm = -50.0, insertion_max_mm = 2500.0;
    static constexpr double roll_min_rad = -838.8608, roll_max_rad = 838.8607;
    static constexpr double position_max_abs_mm = 1000.0;
    static constexpr double quaternion_norm_tolerance = 1e-3;  ///< | |q| - 1 | must be below this
    static constexpr double tip_force_max_abs_N = 25.0;
    static constexpr std::int64_t time_max_us = 1'000'000'000'000'000;  ///< 10^9 s: 31 years
};

/// A problem with one cell of a row: the column and what is wrong (no line number).
struct CellProblem {
    std::string column;
    std::string message;
};
/// The first value of `row` that is not finite or outside RecordingLimits, or a region that is
/// not a colon region name; nullopt if the row is fine.  Time is not checked here.
std::optional<CellProblem> check_row_values(const RecordingRow& row);

/// The row as one CSV line (no newline), every value at its wire resolution.  Throws
/// RecordingError (line 0) if check_row_values finds a problem in the wire-rounded row, or the
/// time is negative.
std::string format_recording_row(const RecordingRow& row);

/// A number as error messages print it (shortest form that reads back to the same double).
std::string shortest_number(double value);
/// time_us as time_s with 6 decimals ("12.000250"); negative times get a leading '-'.
std::string format_time_s(std::int64_t time_us);

/// Writes the header at construction, then one line per row.  Refuses (RecordingError naming the
/// line it would have written) a row the reader would reject: a bad value, a time not later than
/// the previous row's.  Extra columns (names starting with "x_", for humans and other tools) go
/// after the schema's columns; their cells must not contain a comma, quote or line break.
class RecordingWriter {
public:
    explicit RecordingWriter(std::ostream& out, std::vector<std::string> extra_columns = {});
    void write(const RecordingRow& row);
    void write(const RecordingRow& row, const std::vector<std::string>& extra_cells);
    [[nodiscard]] std::size_t rows_written() const { return rows_written_; }
    /// The line the next row goes to (the header is line 1).
    [[nodiscard]] std::size_t next_line() const { return rows_written_ + 2; }

private:
    std::ostream& out_;
    std::vector<std::string> extra_columns_;
    std::size_t rows_written_ = 0;
    std::optional<std::int64_t> last_time_us_;
};

}  // namespace scopekin::recording
