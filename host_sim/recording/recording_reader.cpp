#include "host_sim/recording/recording_reader.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>

#include "host_sim/recording/recording_format.hpp"
#include "model/io/strict_json.hpp"

namespace scopekin::recording {

namespace {

using model::io::quote_text;

constexpr std::size_t kTimeColumn = 0;
constexpr std::size_t kForceColumn = 1;      // force, torque
constexpr std::size_t kInsertionColumn = 3;  // insertion, roll
constexpr std::size_t kEmColumn = 5;         // 7 per sensor
constexpr std::size_t kEmCells = 7;
constexpr std::size_t kTipForceColumn = kEmColumn + kEmSlotCount * kEmCells;  // 33
constexpr std::size_t kRegionColumn = kTipForceColumn + 3;                    // 36

std::vector<std::string> split_cells(const std::string& line) {
    std::vector<std::string> cells;
    std::size_t start = 0;
    while (true) {
        const std::size_t comma = line.find(',', start);
        if (comma == std::string::npos) {
            cells.push_back(line.substr(start));
            return cells;
        }
        cells.push_back(line.substr(start, comma - start));
        start = comma + 1;
    }
}

/// Parses one data line against the header's column mapping.
class LineParser {
public:
    LineParser(const std::string& source, std::size_t line, const std::vector<std::string>& cells,
               const std::vector<std::size_t>& position)
        : source_(source), line_(line), cells_(cells), position_(position) {}

    [[noreturn]] void fail(const std::string& column, const std::string& message) const {
        std::string text = source_.empty() ? "" : source_ + ": ";
        text += "line " + std::to_string(line_);
        if (!column.empty()) text += ", column " + column;
        throw RecordingError(text + ": " + message, line_);
    }

    /// The cell of schema column `column` (recording_columns() index).
    [[nodiscard]] const std::string& cell(std::size_t column) const {
        return cells_[position_[column]];
    }

    [[nodiscard]] double number(std::size_t column) const {
        const std::string& text = cell(column);
        double value = 0;
        const char* begin = text.data();
        const char* end = begin + text.size();
        const auto result = std::from_chars(begin, end, value);
        if (!text.empty() && result.ec == std::errc::result_out_of_range && result.ptr == end) {
            // Beyond double: 1e309 is out of range; 1e-400 is 0, as the JSON readers take it.
            value = std::strtod(text.c_str(), nullptr);
            if (std::isinf(value))
                fail(recording_columns()[column],
                     quote_text(text) +
                         " is out of range (a number's magnitude must be below "
                         "1.8e308)");
            return value;
        }
        if (text.empty() || result.ec != std::errc() || result.ptr != end)
            fail(recording_columns()[column], quote_text(text) + " is not a number");
        if (!std::isfinite(value))
            fail(recording_columns()[column], quote_text(text) + " is not a finite number");
        return value;
    }

    /// time_s: a plain decimal number of seconds with at most 6 decimals, read exactly into µs.
    [[nodiscard]] std::int64_t time_us() const {
        const std::string& text = cell(kTimeColumn);
        const std::string& name = recording_columns()[kTimeColumn];
        std::size_t i = 0;
        std::int64_t seconds = 0;
        std::size_t int_digits = 0;
        while (i < text.size() && text[i] >= '0' && text[i] <= '9') {
            if (++int_digits > 10) fail(name, quote_text(text) + " is too large (at most 10^9 s)");
            seconds = seconds * 10 + (text[i] - '0');
            ++i;
        }
        std::int64_t micro = 0;
        std::size_t decimals = 0;
        if (i < text.size() && text[i] == '.') {
            ++i;
            while (i < text.size() && text[i] >= '0' && text[i] <= '9') {
                if (++decimals > 6)
                    fail(name,
                         quote_text(text) + " has more than 6 decimals (time_s is in whole µs)");
                micro = micro * 10 + (text[i] - '0');
                ++i;
            }
        }
        if (int_digits == 0 || i != text.size() || (i > 0 && text[i - 1] == '.')) {
            // Not the plain form: say what it is, for a better message.
            double value = 0;
            const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
            if (text.empty() || result.ec != std::errc() || result.ptr != text.data() + text.size())
                fail(name, quote_text(text) + " is not a number");
            if (value < 0) fail(name, quote_text(text) + " is negative");
            fail(name, quote_text(text) +
                           " is not written as plain seconds with at most 6 decimals (e.g. "
                           "12.000250)");
        }
        for (std::size_t d = decimals; d < 6; ++d)
            micro *= 10;
        const std::int64_t total = seconds * 1'000'000 + micro;
        if (total > RecordingLimits::time_max_us)
            fail(name, quote_text(text) + " is too large (at most 10^9 s)");
        return total;
    }

    /// Whether the group of `count` columns from `first` is present; throws if partly filled.
    [[nodiscard]] bool group_present(std::size_t first, std::size_t count) const {
        std::optional<std::size_t> filled;
        std::optional<std::size_t> empty;
        for (std::size_t c = first; c < first + count; ++c) {
            if (cell(c).empty()) {
                if (!empty) empty = c;
            } else if (!filled) {
                filled = c;
            }
        }
        if (filled && empty) {
            const auto& columns = recording_columns();
            fail(columns[*empty],
                 "empty, but " + columns[*filled] + " of the same sensor is not (the " +
                     std::to_string(count) + " cells " + columns[first] + " .. " +
                     columns[first + count - 1] + " are one sample: all filled or all empty)");
        }
        return filled.has_value();
    }

private:
    const std::string& source_;
    std::size_t line_;
    const std::vector<std::string>& cells_;
    const std::vector<std::size_t>& position_;
};

}  // namespace

std::vector<RecordingGap> find_gaps(const std::vector<RecordingRow>& rows, double threshold_s) {
    std::vector<RecordingGap> gaps;
    if (rows.empty()) return gaps;
    const auto threshold_us = static_cast<std::int64_t>(std::llround(threshold_s * 1e6));
    const std::int64_t first = rows.front().time_us;
    const std::int64_t last = rows.back().time_us;
    auto to_s = [](std::int64_t us) { return static_cast<double>(us) / 1e6; };
    for (int signal = 0; signal < 2; ++signal) {
        const char* name = signal == 0 ? "handle_force_torque" : "insertion_roll";
        std::int64_t previous = first;
        for (const RecordingRow& row : rows) {
            const bool delivered =
                signal == 0 ? row.handle.has_value() : row.insertion_roll.has_value();
            if (!delivered) continue;
            if (row.time_us - previous > threshold_us)
                gaps.push_back({to_s(previous), to_s(row.time_us), name});
            previous = row.time_us;
        }
        if (last - previous > threshold_us) gaps.push_back({to_s(previous), to_s(last), name});
    }
    return gaps;
}

RecordingReader::RecordingReader(RecordingReaderOptions options) : options_(options) {
    if (!(options_.gap_threshold_s > 0) || !std::isfinite(options_.gap_threshold_s))
        throw RecordingError(
            "gap threshold " + shortest_number(options_.gap_threshold_s) + " s must be > 0", 0);
    if (!(options_.max_gap_s > 0) || !std::isfinite(options_.max_gap_s))
        throw RecordingError("the longest gap between rows " + shortest_number(options_.max_gap_s) +
                                 " s must be a positive, finite number",
                             0);
}

Recording RecordingReader::read_file(const std::string& path) const {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw RecordingError(path + ": cannot open the file", 0);
    return read(in, path);
}

Recording RecordingReader::read(std::istream& in, const std::string& source) const {
    const std::string prefix = source.empty() ? "" : source + ": ";
    const std::vector<std::string>& columns = recording_columns();
    Recording recording;

    std::string text;
    if (!std::getline(in, text))
        throw RecordingError(prefix + "line 1: the file is empty (expected the header)", 1);
    if (!text.empty() && text.back() == '\r') text.pop_back();
    // A UTF-8 byte-order mark (some spreadsheets write one) is not part of the first column's name.
    if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);

    // --- header: every schema column once, extra columns only with the x_ prefix -------------------
    const std::vector<std::string> header = split_cells(text);
    std::vector<std::size_t> position(columns.size(), header.size());  // header.size() = missing
    std::vector<std::size_t> extra_positions;
    std::map<std::string, std::size_t> seen;
    for (std::size_t i = 0; i < header.size(); ++i) {
        const std::string& name = header[i];
        if (!seen.emplace(name, i).second)
            throw RecordingError(prefix + "line 1: column " + quote_text(name) + " appears twice",
                                 1);
        bool known = false;
        for (std::size_t c = 0; c < columns.size(); ++c) {
            if (columns[c] == name) {
                position[c] = i;
                known = true;
            }
        }
        if (known) continue;
        if (name.rfind("x_", 0) == 0 && name.size() > 2) {
            // As the writer: no quote or carriage return (the file is not quoted CSV).
            if (name.find_first_of("\"\r") != std::string::npos)
                throw RecordingError(prefix + "line 1: extra column " + quote_text(name) +
                                         " holds a quote or a carriage return (not allowed in a "
                                         "recording's cells)",
                                     1);
            recording.extra_columns.push_back(name);
            extra_positions.push_back(i);
            continue;
        }
        throw RecordingError(prefix + "line 1: unknown column " + quote_text(name) +
                                 " (extra columns are allowed only with a name starting with 'x_')",
                             1);
    }
    std::string missing;
    for (std::size_t c = 0; c < columns.size(); ++c)
        if (position[c] == header.size())
            missing += (missing.empty() ? "'" : ", '") + columns[c] + "'";
    if (!missing.empty()) throw RecordingError(prefix + "line 1: missing column " + missing, 1);

    // --- rows --------------------------------------------------------------------------------------
    std::size_t line = 1;
    std::string previous_time_text;
    // The bound in µs; beyond the largest time a recording holds it bounds nothing.
    const std::int64_t max_gap_us =
        options_.max_gap_s * 1e6 >= static_cast<double>(RecordingLimits::time_max_us)
            ? RecordingLimits::time_max_us
            : std::llround(options_.max_gap_s * 1e6);
    while (std::getline(in, text)) {
        ++line;
        if (!text.empty() && text.back() == '\r') text.pop_back();
        if (text.empty())
            throw RecordingError(prefix + "line " + std::to_string(line) +
                                     ": empty line (every line after the header is a row)",
                                 line);
        const std::vector<std::string> cells = split_cells(text);
        if (cells.size() != header.size())
            throw RecordingError(prefix + "line " + std::to_string(line) + ": " +
                                     std::to_string(cells.size()) + " cells, the header has " +
                                     std::to_string(header.size()) + " columns",
                                 line);
        const LineParser parser(source, line, cells, position);
        RecordingRow row;
        row.time_us = parser.time_us();
        if (!recording.rows.empty() && row.time_us <= recording.rows.back().time_us)
            parser.fail("", "time_s " + parser.cell(kTimeColumn) + " is not later than line " +
                                std::to_string(recording.row_lines.back()) + "'s " +
                                previous_time_text);
        if (!recording.rows.empty() && row.time_us - recording.rows.back().time_us > max_gap_us)
            parser.fail("", "time_s " + parser.cell(kTimeColumn) + " is " +
                                format_time_s(row.time_us - recording.rows.back().time_us) +
                                " s after line " + std::to_string(recording.row_lines.back()) +
                                "'s " + previous_time_text + ": a gap between rows longer than " +
                                shortest_number(options_.max_gap_s) +
                                " s is refused (a run would step across all of it; --max-gap-s "
                                "raises the bound)");
        previous_time_text = parser.cell(kTimeColumn);

        if (parser.group_present(kForceColumn, 2))
            row.handle =
                ForceTorqueCells{parser.number(kForceColumn), parser.number(kForceColumn + 1)};
        if (parser.group_present(kInsertionColumn, 2))
            row.insertion_roll = InsertionRollCells{parser.number(kInsertionColumn),
                                                    parser.number(kInsertionColumn + 1)};
        for (std::size_t slot = 0; slot < kEmSlotCount; ++slot) {
            const std::size_t first = kEmColumn + slot * kEmCells;
            if (!parser.group_present(first, kEmCells)) continue;
            EmPoseCells pose;
            for (std::size_t i = 0; i < 3; ++i)
                pose.position_mm[i] = parser.number(first + i);
            for (std::size_t i = 0; i < 4; ++i)
                pose.quaternion_wxyz[i] = parser.number(first + 3 + i);
            row.em[slot] = pose;
        }
        if (parser.group_present(kTipForceColumn, 3)) {
            TipForceCells force;
            for (std::size_t i = 0; i < 3; ++i)
                force.force_N[i] = parser.number(kTipForceColumn + i);
            row.tip_force = force;
        }
        row.region = parser.cell(kRegionColumn);
        if (const auto problem = check_row_values(row))
            parser.fail(problem->column, problem->message);

        std::vector<std::string> extras;
        extras.reserve(extra_positions.size());
        for (std::size_t k = 0; k < extra_positions.size(); ++k) {
            const std::string& cell = cells[extra_positions[k]];
            // As the writer: no quote or carriage return (the file is not quoted CSV).
            if (cell.find_first_of("\"\r") != std::string::npos)
                parser.fail(recording.extra_columns[k],
                            quote_text(cell) +
                                " holds a quote or a carriage return (not allowed in a "
                                "recording's cells)");
            extras.push_back(cell);
        }
        recording.rows.push_back(std::move(row));
        recording.row_lines.push_back(line);
        recording.extra_cells.push_back(std::move(extras));
    }
    if (in.bad())
        throw RecordingError(prefix + "line " + std::to_string(line + 1) + ": read error",
                             line + 1);
    recording.gaps = find_gaps(recording.rows, options_.gap_threshold_s);
    return recording;
}

}  // namespace scopekin::recording
