#include "host_sim/recording/recording_format.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <set>

#include "host_sim/recording/wire_values.hpp"
#include "model/colon/colon_region.hpp"
#include "model/io/strict_json.hpp"

namespace scopekin::recording {

namespace {

constexpr std::array<std::string_view, kEmSlotCount> kEmPrefixes{"em_tip", "em_20cm", "em_handle",
                                                                 "em_sigmoid"};

std::vector<std::string> make_columns() {
    std::vector<std::string> columns{"time_s", "handle_force_N", "handle_torque_Nmm",
                                     "insertion_mm", "roll_rad"};
    for (std::string_view prefix : kEmPrefixes) {
        const std::string p(prefix);
        for (const char* suffix : {"_x_mm", "_y_mm", "_z_mm", "_qw", "_qx", "_qy", "_qz"})
            columns.push_back(p + suffix);
    }
    for (const char* c : {"tip_force_x_N", "tip_force_y_N", "tip_force_z_N", "region"})
        columns.emplace_back(c);
    return columns;
}

/// `scaled` in units of 10^-decimals, printed exactly ("-1.235" for -1235 with 3 decimals).
std::string format_fixed(std::int64_t scaled, int decimals) {
    const bool negative = scaled < 0;
    const std::uint64_t magnitude = negative ? std::uint64_t{0} - static_cast<std::uint64_t>(scaled)
                                             : static_cast<std::uint64_t>(scaled);
    std::uint64_t divisor = 1;
    for (int i = 0; i < decimals; ++i)
        divisor *= 10U;
    std::string fraction = std::to_string(magnitude % divisor);
    fraction.insert(0, static_cast<std::size_t>(decimals) - fraction.size(), '0');
    std::string out = negative ? "-" : "";
    out += std::to_string(magnitude / divisor);
    if (decimals > 0) out += "." + fraction;
    return out;
}

/// A Q2.14 component at 6 decimals: round(q14 * 10^6 / 16384), ties away from zero, exact.
std::string format_q14(std::int64_t q14) {
    const std::int64_t magnitude = q14 < 0 ? -q14 : q14;
    const std::int64_t micro = (2 * magnitude * 1'000'000 + 16384) / 32768;
    return format_fixed(q14 < 0 ? -micro : micro, 6);
}

/// value must be finite and within [lo, hi] once rounded to the wire's `step` (so 32767 × 0.1,
/// which is 3276.7000000000003 in double, is within [.., 3276.7]).
std::optional<CellProblem> check_range(double value, double lo, double hi, double step,
                                       const std::string& column) {
    if (!std::isfinite(value))
        return CellProblem{column, shortest_number(value) + " is not a finite number"};
    if (value < lo - 0.5 * step || value > hi + 0.5 * step)
        return CellProblem{column, shortest_number(value) + " is outside the plausible range [" +
                                       shortest_number(lo) + ", " + shortest_number(hi) + "]"};
    return std::nullopt;
}

}  // namespace

std::string_view em_slot_prefix(std::size_t slot) {
    return slot < kEmSlotCount ? kEmPrefixes[slot] : "";
}

bool RecordingRow::has_sensor_data() const {
    if (handle || insertion_roll || tip_force) return true;
    for (const auto& pose : em)
        if (pose) return true;
    return false;
}

const std::vector<std::string>& recording_columns() {
    static const std::vector<std::string> columns = make_columns();
    return columns;
}

std::string recording_header() {
    std::string header;
    for (const std::string& c : recording_columns())
        header += (header.empty() ? "" : ",") + c;
    return header;
}

std::string csv_cell(std::string_view text) {
    if (text.find_first_of(",\"\n\r") == std::string_view::npos) return std::string(text);
    std::string quoted = "\"";
    for (const char c : text) {
        if (c == '"') quoted += '"';
        quoted += c == '\n' || c == '\r' ? ' ' : c;
    }
    return quoted + "\"";
}

std::string shortest_number(double value) {
    if (std::isnan(value)) return "nan";
    if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    return std::string(buffer, result.ptr);
}

std::string format_time_s(std::int64_t time_us) {
    return format_fixed(time_us, 6);
}

std::optional<CellProblem> check_row_values(const RecordingRow& row) {
    using L = RecordingLimits;
    std::optional<CellProblem> problem;
    if (row.handle) {
        if ((problem = check_range(row.handle->force_N, L::force_min_N, L::force_max_N, 0.005,
                                   "handle_force_N")))
            return problem;
        if ((problem = check_range(row.handle->torque_Nmm, L::torque_min_Nmm, L::torque_max_Nmm,
                                   0.1, "handle_torque_Nmm")))
            return problem;
    }
    if (row.insertion_roll) {
        if ((problem = check_range(row.insertion_roll->insertion_mm, L::insertion_min_mm,
                                   L::insertion_max_mm, 0.01, "insertion_mm")))
            return problem;
        if ((problem = check_range(row.insertion_roll->roll_rad, L::roll_min_rad, L::roll_max_rad,
                                   0.0001, "roll_rad")))
            return problem;
    }
    static constexpr std::array<const char*, 3> kAxes{"_x_mm", "_y_mm", "_z_mm"};
    static constexpr std::array<const char*, 4> kQuaternion{"_qw", "_qx", "_qy", "_qz"};
    for (std::size_t slot = 0; slot < kEmSlotCount; ++slot) {
        const auto& pose = row.em[slot];
        if (!pose) continue;
        const std::string prefix(kEmPrefixes[slot]);
        for (std::size_t i = 0; i < 3; ++i) {
            if ((problem = check_range(pose->position_mm[i], -L::position_max_abs_mm,
                                       L::position_max_abs_mm, 0.001, prefix + kAxes[i])))
                return problem;
        }
        double norm2 = 0;
        for (std::size_t i = 0; i < 4; ++i) {
            const double q = pose->quaternion_wxyz[i];
            if (!std::isfinite(q))
                return CellProblem{prefix + kQuaternion[i],
                                   shortest_number(q) + " is not a finite number"};
            norm2 += q * q;
        }
        const double norm = std::sqrt(norm2);
        if (!(std::abs(norm - 1.0) < L::quaternion_norm_tolerance))
            return CellProblem{prefix + "_qw", "the quaternion's norm " + shortest_number(norm) +
                                                   " is not 1 (tolerance " +
                                                   shortest_number(L::quaternion_norm_tolerance) +
                                                   ")"};
    }
    if (row.tip_force) {
        static constexpr std::array<const char*, 3> kForce{"tip_force_x_N", "tip_force_y_N",
                                                           "tip_force_z_N"};
        for (std::size_t i = 0; i < 3; ++i) {
            if ((problem = check_range(row.tip_force->force_N[i], -L::tip_force_max_abs_N,
                                       L::tip_force_max_abs_N, 0.001, kForce[i])))
                return problem;
        }
    }
    if (!row.region.empty() && !model::region_from_name(row.region)) {
        std::string names;
        for (model::ColonRegion r : model::kColonRegionsInOrder)
            names += (names.empty() ? "" : ", ") + std::string(model::region_name(r));
        return CellProblem{"region", model::io::quote_text(row.region) +
                                         " is not a colon region (" + names + ", or empty)"};
    }
    return std::nullopt;
}

std::string format_recording_row(const RecordingRow& input) {
    if (input.time_us < 0 || input.time_us > RecordingLimits::time_max_us)
        throw RecordingError(
            "column time_s: " + format_time_s(input.time_us) + " s is outside [0, 10^9] s", 0);
    const RecordingRow row = wire::quantize_to_wire(input);
    // Check the raw input too: a NaN quantises to 0 and would otherwise pass.
    for (const RecordingRow* r : {&input, &row}) {
        if (const auto problem = check_row_values(*r))
            throw RecordingError("column " + problem->column + ": " + problem->message, 0);
    }
    std::string line = format_time_s(input.time_us);
    auto cell = [&line](const std::string& text) {
        line += ',';
        line += text;
    };
    if (row.handle) {
        cell(format_fixed(wire::handle_force_raw(row.handle->force_N) * 5, 3));  // raw × 0.005 N
        cell(format_fixed(wire::handle_torque_raw(row.handle->torque_Nmm), 1));
    } else {
        line += ",,";
    }
    if (row.insertion_roll) {
        cell(format_fixed(wire::insertion_raw(row.insertion_roll->insertion_mm), 2));
        cell(format_fixed(wire::roll_raw(row.insertion_roll->roll_rad), 4));
    } else {
        line += ",,";
    }
    for (const auto& pose : row.em) {
        if (pose) {
            for (double p : pose->position_mm)
                cell(format_fixed(wire::position_um(p), 3));
            for (double q : pose->quaternion_wxyz)
                cell(format_q14(wire::quaternion_q14(q)));
        } else {
            line += ",,,,,,,";
        }
    }
    if (row.tip_force) {
        for (double f : row.tip_force->force_N)
            cell(format_fixed(wire::tip_force_mN(f), 3));
    } else {
        line += ",,,";
    }
    cell(row.region);
    return line;
}

RecordingWriter::RecordingWriter(std::ostream& out, std::vector<std::string> extra_columns)
    : out_(out), extra_columns_(std::move(extra_columns)) {
    std::set<std::string> seen(recording_columns().begin(), recording_columns().end());
    for (const std::string& name : extra_columns_) {
        if (name.rfind("x_", 0) != 0 || name.size() < 3)
            throw RecordingError(
                "line 1: extra column " + model::io::quote_text(name) + " must start with 'x_'", 1);
        if (name.find_first_of(",\"\r\n") != std::string::npos)
            throw RecordingError("line 1: extra column " + model::io::quote_text(name) +
                                     " contains a comma, quote or line break",
                                 1);
        if (!seen.insert(name).second)
            throw RecordingError("line 1: column " + model::io::quote_text(name) + " appears twice",
                                 1);
    }
    std::string header = recording_header();
    for (const std::string& name : extra_columns_)
        header += "," + name;
    out_ << header << '\n';
}

void RecordingWriter::write(const RecordingRow& row) {
    write(row, {});
}

void RecordingWriter::write(const RecordingRow& row, const std::vector<std::string>& extra_cells) {
    const std::size_t line_number = next_line();
    const std::string where = "line " + std::to_string(line_number);
    if (!extra_cells.empty() && extra_cells.size() != extra_columns_.size())
        throw RecordingError(where + ": " + std::to_string(extra_cells.size()) +
                                 " extra cells for " + std::to_string(extra_columns_.size()) +
                                 " extra columns",
                             line_number);
    if (last_time_us_ && row.time_us <= *last_time_us_)
        throw RecordingError(where + ": time_s " + format_time_s(row.time_us) +
                                 " is not later than line " + std::to_string(line_number - 1) +
                                 "'s " + format_time_s(*last_time_us_),
                             line_number);
    std::string line;
    try {
        line = format_recording_row(row);
    } catch (const RecordingError& e) {
        throw RecordingError(where + ", " + e.what(), line_number);
    }
    for (std::size_t i = 0; i < extra_columns_.size(); ++i) {
        const std::string text = extra_cells.empty() ? std::string() : extra_cells[i];
        if (text.find_first_of(",\"\r\n") != std::string::npos)
            throw RecordingError(where + ", column " + extra_columns_[i] +
                                     ": a comma, quote or line break in the cell",
                                 line_number);
        line += "," + text;
    }
    out_ << line << '\n';
    if (!out_) throw RecordingError(where + ": the output stream failed", line_number);
    last_time_us_ = row.time_us;
    ++rows_written_;
}

}  // namespace scopekin::recording
