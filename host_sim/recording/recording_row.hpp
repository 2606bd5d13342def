#pragma once
// One row of a recording (host_sim/recording/RECORDING.md): what reached the sensor box, or the
// bench logger, at one instant.  Every sensor group is optional: a group is present exactly when
// that sensor delivered a sample at `time_us`.
//
// Units are those of the CSV columns: N, N·mm, mm, rad; positions in the colon frame (which the
// simulator uses as the EM tracker's frame); quaternions unit, (w, x, y, z), rotating sensor-frame
// vectors into the colon frame.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace scopekin::recording {

/// A malformed recording (reader) or a row that cannot be written (writer).  `line()` is the
/// 1-based line of the file the problem is on (0 when there is no line, e.g. a file that cannot
/// be opened); the message starts with "line N" where there is one.
class RecordingError : public std::runtime_error {
public:
    RecordingError(const std::string& message, std::size_t line)
        : std::runtime_error(message), line_(line) {}
    [[nodiscard]] std::size_t line() const { return line_; }

private:
    std::size_t line_;
};

/// Handle force/torque cell (CAN 0x110): one frame carries both.
struct ForceTorqueCells {
    double force_N = 0;     ///< axial, + pushing in
    double torque_Nmm = 0;  ///< about the shaft axis
    friend bool operator==(const ForceTorqueCells&, const ForceTorqueCells&) = default;
};

/// Insertion/roll encoder (CAN 0x111): one frame carries both.
struct InsertionRollCells {
    double insertion_mm = 0;  ///< scope length past the anus
    double roll_rad = 0;      ///< unwrapped
    friend bool operator==(const InsertionRollCells&, const InsertionRollCells&) = default;
};

/// One EM tracker sensor's pose (serial pose frame).
struct EmPoseCells {
    std::array<double, 3> position_mm{};                        ///< x, y, z, colon frame
    std::array<double, 4> quaternion_wxyz{1.0, 0.0, 0.0, 0.0};  ///< unit
    friend bool operator==(const EmPoseCells&, const EmPoseCells&) = default;
};

/// Tip contact force (serial tip force frame), tip frame: x, y across the tip, z along the axis.
struct TipForceCells {
    std::array<double, 3> force_N{};
    friend bool operator==(const TipForceCells&, const TipForceCells&) = default;
};

/// The four EM tracker sensors; the index is the wire's sensor id (em_tracker_serial.md §3).
enum class EmSlot : std::uint8_t {
    tip = 0,
    twenty_cm = 1,
    handle = 2,
    sigmoid = 3
};
inline constexpr std::size_t kEmSlotCount = 4;
/// Column prefix of each EM sensor, by wire id: "em_tip", "em_20cm", "em_handle", "em_sigmoid".
std::string_view em_slot_prefix(std::size_t slot);

struct RecordingRow {
    std::int64_t time_us = 0;  ///< >= 0; printed as time_s with 6 decimals
    std::optional<ForceTorqueCells> handle;
    std::optional<InsertionRollCells> insertion_roll;
    std::array<std::optional<EmPoseCells>, kEmSlotCount> em{};  ///< by wire sensor id
    std::optional<TipForceCells> tip_force;
    std::string
        region;  ///< colon region of the tip (model/colon/colon_region.hpp names), "" = unknown

    /// True if at least one sensor group is present.
    [[nodiscard]] bool has_sensor_data() const;
    friend bool operator==(const RecordingRow&, const RecordingRow&) = default;
};

}  // namespace scopekin::recording
