#include "host_sim/recording/wire_values.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "protocol/can/can_signal.hpp"

namespace scopekin::recording::wire {
namespace {

// Raw counts per physical unit (the inverse of each resolution; all exact in double).
constexpr double kForcePerN = 200.0;         // 0.005 N
constexpr double kTorquePerNmm = 10.0;       // 0.1 N·mm
constexpr double kInsertionPerMm = 100.0;    // 0.01 mm
constexpr double kRollPerRad = 10000.0;      // 0.0001 rad
constexpr double kUmPerMm = 1000.0;          // 1 µm
constexpr double kQ14PerUnit = 16384.0;      // Q2.14
constexpr double kMilliNewtonPerN = 1000.0;  // 1 mN

constexpr std::int64_t kInt16Min = std::numeric_limits<std::int16_t>::min();
constexpr std::int64_t kInt16Max = std::numeric_limits<std::int16_t>::max();
constexpr std::int64_t kInt24Min = -(std::int64_t{1} << 23);
constexpr std::int64_t kInt24Max = (std::int64_t{1} << 23) - 1;
constexpr std::int64_t kInt32Min = std::numeric_limits<std::int32_t>::min();
constexpr std::int64_t kInt32Max = std::numeric_limits<std::int32_t>::max();

/// round(value * scale), ties away from zero, saturated to [lo, hi]; 0 for NaN / infinity.
std::int64_t round_scaled(double value, double scale, std::int64_t lo, std::int64_t hi) {
    if (!std::isfinite(value)) return 0;
    const double x = value * scale;
    if (x <= static_cast<double>(lo)) return lo;
    if (x >= static_cast<double>(hi)) return hi;
    return static_cast<std::int64_t>(std::llround(x));
}

const protocol::CanSignal& layout_signal(std::uint32_t id, std::size_t index) {
    const protocol::MessageLayout* layout = protocol::find_message_layout(id);
    // The codec defines both messages; a missing layout would be a build of another protocol.
    if (layout == nullptr || index >= layout->signals.size())
        throw std::logic_error("CAN layout not found");
    return layout->signals[index];
}

fixed_point::Q16_16 q16_of_raw(std::int64_t raw, const protocol::CanSignal& signal) {
    bool saturated = false;
    return protocol::raw_to_q16(raw, signal, saturated);
}

std::int64_t raw_of_q16(fixed_point::Q16_16 value, const protocol::CanSignal& signal) {
    bool saturated = false;
    return protocol::q16_to_raw(value, signal, saturated);
}

}  // namespace

std::int64_t handle_force_raw(double force_N) {
    return round_scaled(force_N, kForcePerN, kInt16Min, kInt16Max);
}
std::int64_t handle_torque_raw(double torque_Nmm) {
    return round_scaled(torque_Nmm, kTorquePerNmm, kInt16Min, kInt16Max);
}
std::int64_t insertion_raw(double insertion_mm) {
    return round_scaled(insertion_mm, kInsertionPerMm, kInt24Min, kInt24Max);
}
std::int64_t roll_raw(double roll_rad) {
    return round_scaled(roll_rad, kRollPerRad, kInt24Min, kInt24Max);
}
std::int32_t position_um(double position_mm) {
    return static_cast<std::int32_t>(round_scaled(position_mm, kUmPerMm, kInt32Min, kInt32Max));
}
std::int16_t quaternion_q14(double component) {
    return static_cast<std::int16_t>(round_scaled(component, kQ14PerUnit, kInt16Min, kInt16Max));
}
std::int16_t tip_force_mN(double force_N) {
    return static_cast<std::int16_t>(round_scaled(force_N, kMilliNewtonPerN, kInt16Min, kInt16Max));
}

double handle_force_value(std::int64_t raw) {
    return static_cast<double>(raw) / kForcePerN;
}
double handle_torque_value(std::int64_t raw) {
    return static_cast<double>(raw) / kTorquePerNmm;
}
double insertion_value(std::int64_t raw) {
    return static_cast<double>(raw) / kInsertionPerMm;
}
double roll_value(std::int64_t raw) {
    return static_cast<double>(raw) / kRollPerRad;
}
double position_value(std::int64_t um) {
    return static_cast<double>(um) / kUmPerMm;
}
double quaternion_value(std::int64_t q14) {
    return static_cast<double>(q14) / kQ14PerUnit;
}
double tip_force_value(std::int64_t mN) {
    return static_cast<double>(mN) / kMilliNewtonPerN;
}

RecordingRow quantize_to_wire(const RecordingRow& row) {
    RecordingRow out = row;
    if (out.handle) {
        out.handle->force_N = handle_force_value(handle_force_raw(row.handle->force_N));
        out.handle->torque_Nmm = handle_torque_value(handle_torque_raw(row.handle->torque_Nmm));
    }
    if (out.insertion_roll) {
        out.insertion_roll->insertion_mm =
            insertion_value(insertion_raw(row.insertion_roll->insertion_mm));
        out.insertion_roll->roll_rad = roll_value(roll_raw(row.insertion_roll->roll_rad));
    }
    for (auto& pose : out.em) {
        if (!pose) continue;
        for (double& p : pose->position_mm)
            p = position_value(position_um(p));
        for (double& q : pose->quaternion_wxyz)
            q = quaternion_value(quaternion_q14(q));
    }
    if (out.tip_force) {
        for (double& f : out.tip_force->force_N)
            f = tip_force_value(tip_force_mN(f));
    }
    return out;
}

const protocol::CanSignal& handle_force_signal() {
    return layout_signal(protocol::kHandleForceTorqueId, 0);
}
const protocol::CanSignal& handle_torque_signal() {
    return layout_signal(protocol::kHandleForceTorqueId, 1);
}
const protocol::CanSignal& insertion_signal() {
    return layout_signal(protocol::kInsertionRollId, 0);
}
const protocol::CanSignal& roll_signal() {
    return layout_signal(protocol::kInsertionRollId, 1);
}

protocol::HandleForceTorque to_handle_force_torque(const ForceTorqueCells& cells,
                                                   std::uint8_t counter) {
    protocol::HandleForceTorque message{};
    message.force_N = q16_of_raw(handle_force_raw(cells.force_N), handle_force_signal());
    message.torque_Nmm = q16_of_raw(handle_torque_raw(cells.torque_Nmm), handle_torque_signal());
    message.status = 0;
    message.counter = static_cast<std::uint8_t>(counter & 0x0FU);
    return message;
}

protocol::InsertionRoll to_insertion_roll(const InsertionRollCells& cells, std::uint8_t counter) {
    protocol::InsertionRoll message{};
    message.insertion_mm = q16_of_raw(insertion_raw(cells.insertion_mm), insertion_signal());
    message.roll_rad = q16_of_raw(roll_raw(cells.roll_rad), roll_signal());
    message.status = 0;
    message.counter = static_cast<std::uint8_t>(counter & 0x0FU);
    return message;
}

protocol::EmPoseMessage to_em_pose(const EmPoseCells& cells, std::uint8_t sensor_id,
                                   std::uint32_t device_time_us) {
    protocol::EmPoseMessage message{};
    message.device_time_us = device_time_us;
    message.sensor_id = sensor_id;
    message.status = 0;
    for (std::size_t i = 0; i < 3; ++i)
        message.position_um[i] = position_um(cells.position_mm[i]);
    for (std::size_t i = 0; i < 4; ++i)
        message.orientation_q14[i] = quaternion_q14(cells.quaternion_wxyz[i]);
    return message;
}

protocol::TipForceMessage to_tip_force(const TipForceCells& cells, std::uint32_t device_time_us) {
    protocol::TipForceMessage message{};
    message.device_time_us = device_time_us;
    message.status = 0;
    for (std::size_t i = 0; i < 3; ++i)
        message.force_mN[i] = tip_force_mN(cells.force_N[i]);
    return message;
}

ForceTorqueCells from_message(const protocol::HandleForceTorque& message) {
    return {handle_force_value(raw_of_q16(message.force_N, handle_force_signal())),
            handle_torque_value(raw_of_q16(message.torque_Nmm, handle_torque_signal()))};
}

InsertionRollCells from_message(const protocol::InsertionRoll& message) {
    return {insertion_value(raw_of_q16(message.insertion_mm, insertion_signal())),
            roll_value(raw_of_q16(message.roll_rad, roll_signal()))};
}

EmPoseCells from_message(const protocol::EmPoseMessage& message) {
    EmPoseCells cells;
    for (std::size_t i = 0; i < 3; ++i)
        cells.position_mm[i] = position_value(message.position_um[i]);
    for (std::size_t i = 0; i < 4; ++i)
        cells.quaternion_wxyz[i] = quaternion_value(message.orientation_q14[i]);
    return cells;
}

TipForceCells from_message(const protocol::TipForceMessage& message) {
    TipForceCells cells;
    for (std::size_t i = 0; i < 3; ++i)
        cells.force_N[i] = tip_force_value(message.force_mN[i]);
    return cells;
}

}  // namespace scopekin::recording::wire
