#pragma once
// What the wire carries for each recording cell: the raw integer of the signal, the physical value
// of a raw integer, and the protocol messages built from a row's groups.
//
// Resolutions (one raw count):
//   handle_force_N      0.005 N       CAN 0x110 HandleForce, int16   (scopekin.dbc)
//   handle_torque_Nmm   0.1 N·mm      CAN 0x110 HandleTorque, int16
//   insertion_mm        0.01 mm       CAN 0x111 Insertion, int24
//   roll_rad            0.0001 rad    CAN 0x111 Roll, int24
//   em_*_{x,y,z}_mm     0.001 mm      serial pose, int32 µm        (em_tracker_serial.md §3)
//   em_*_q{w,x,y,z}     1/16384       serial pose, int16 Q2.14
//   tip_force_*_N       0.001 N       serial tip force, int16 mN
// raw = round(value / resolution), ties away from zero, saturated to the signal's integer range
// (as the protocol's encoders saturate).  A non-finite value gives raw 0 (callers check first).
//
// The CAN messages carry Q16.16 values.  to_handle_force_torque / to_insertion_roll build the
// Q16.16 value from the raw integer with the CAN decoder's own conversion (protocol::raw_to_q16),
// so that protocol::encode gives back exactly that raw integer: the Q16.16 step (1.5e-5) is far
// below half of every resolution above, so the round trip raw -> Q16.16 -> raw is exact.
#include <cstdint>

#include "host_sim/recording/recording_row.hpp"
#include "protocol/can/scopekin_messages.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace scopekin::recording::wire {

// ---- raw integers -------------------------------------------------------------------------------
[[nodiscard]] std::int64_t handle_force_raw(double force_N);
[[nodiscard]] std::int64_t handle_torque_raw(double torque_Nmm);
[[nodiscard]] std::int64_t insertion_raw(double insertion_mm);
[[nodiscard]] std::int64_t roll_raw(double roll_rad);
[[nodiscard]] std::int32_t position_um(double position_mm);
[[nodiscard]] std::int16_t quaternion_q14(double component);
[[nodiscard]] std::int16_t tip_force_mN(double force_N);

// ---- physical value of a raw integer (the nearest double to raw × resolution) -------------------
[[nodiscard]] double handle_force_value(std::int64_t raw);
[[nodiscard]] double handle_torque_value(std::int64_t raw);
[[nodiscard]] double insertion_value(std::int64_t raw);
[[nodiscard]] double roll_value(std::int64_t raw);
[[nodiscard]] double position_value(std::int64_t um);
[[nodiscard]] double quaternion_value(std::int64_t q14);
[[nodiscard]] double tip_force_value(std::int64_t mN);

/// The row with every value replaced by what the wire carries (raw integer back to a value).
[[nodiscard]] RecordingRow quantize_to_wire(const RecordingRow& row);

// ---- protocol messages --------------------------------------------------------------------------
/// The CAN signal layout of the codec (protocol::find_message_layout): HandleForce, HandleTorque
/// (0x110), Insertion, Roll (0x111).
[[nodiscard]] const protocol::CanSignal& handle_force_signal();
[[nodiscard]] const protocol::CanSignal& handle_torque_signal();
[[nodiscard]] const protocol::CanSignal& insertion_signal();
[[nodiscard]] const protocol::CanSignal& roll_signal();

/// Status 0 (valid), the given 4-bit counter.
[[nodiscard]] protocol::HandleForceTorque to_handle_force_torque(const ForceTorqueCells& cells,
                                                                 std::uint8_t counter);
[[nodiscard]] protocol::InsertionRoll to_insertion_roll(const InsertionRollCells& cells,
                                                        std::uint8_t counter);
/// Status 0; the device time is the row's time in µs modulo 2^32 (the tracker clock wraps).
[[nodiscard]] protocol::EmPoseMessage to_em_pose(const EmPoseCells& cells, std::uint8_t sensor_id,
                                                 std::uint32_t device_time_us);
[[nodiscard]] protocol::TipForceMessage to_tip_force(const TipForceCells& cells,
                                                     std::uint32_t device_time_us);

/// The inverse of the above for decoded messages (tests, a recorder on the box side).
[[nodiscard]] ForceTorqueCells from_message(const protocol::HandleForceTorque& message);
[[nodiscard]] InsertionRollCells from_message(const protocol::InsertionRoll& message);
[[nodiscard]] EmPoseCells from_message(const protocol::EmPoseMessage& message);
[[nodiscard]] TipForceCells from_message(const protocol::TipForceMessage& message);

}  // namespace scopekin::recording::wire
