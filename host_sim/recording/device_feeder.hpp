#pragma once
// Turns recording rows into what the sensor box's peripherals receive: CAN frames of the handle
// sensors on a hal::CanBus (the world end of the simulator's LoopbackCanWire) and EM tracker /
// tip force frames on the serial line (LoopbackSerialPort::device_write).
//
// * CAN: HandleForceTorque (0x110) from handle_force_N / handle_torque_Nmm, InsertionRoll (0x111)
//   from insertion_mm / roll_rad, encoded by the protocol's `encode`, status 0 (valid).  Each
//   message has its own 4-bit rolling counter, 0 in the first frame and +1 per frame sent
//   (send() returned ok).  A recording carries no counters: the feeder numbers the frames it
//   sends, so a sample missing from the recording (a dropout upstream) reaches the box as a
//   longer silence (staleness), never as a counter gap.
// * Serial: one pose frame per EM sensor present, in wire id order (0 tip, 1 20 cm from the tip,
//   2 handle, 3 sigmoid: em_tracker_serial.md §3), then the tip force frame; status 0, device time
//   = the row's time in µs modulo 2^32 (the tracker clock wraps, as the spec allows).
// * Time: the frames go out at the row's time.  Given a SimulatedClock, feed() first advances it
//   to the row's time (never backwards); otherwise the caller sets the clock the wire stamps with.
// Values are rounded to the wire's resolution exactly as format_recording_row prints them
// (wire_values.hpp), so a recorded file and the frames made from it carry the same integers.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>

#include "hal/can_bus.hpp"
#include "hal/loopback/loopback_serial.hpp"
#include "hal/loopback/simulated_clock.hpp"
#include "host_sim/recording/recording_row.hpp"

namespace scopekin::recording {

struct DeviceFeederCounters {
    std::uint64_t rows = 0;                        ///< feed() calls
    std::uint64_t handle_force_torque_frames = 0;  ///< 0x110 frames sent
    std::uint64_t insertion_roll_frames = 0;       ///< 0x111 frames sent
    std::uint64_t can_send_failures =
        0;  ///< send() did not return ok (frame not sent, counter kept)
    std::array<std::uint64_t, kEmSlotCount> em_pose_frames{};  ///< by wire sensor id
    std::uint64_t tip_force_frames = 0;
    std::uint64_t serial_bytes_written = 0;  ///< bytes the line took
    std::uint64_t serial_bytes_lost = 0;     ///< bytes the line could not take (full buffer)
    std::uint64_t serial_frames_without_port =
        0;  ///< EM / tip force samples with no serial sink set
};

class DeviceFeeder {
public:
    /// The device side of a serial line: writes bytes, returns how many the line took.
    using SerialSink = std::function<std::size_t(std::span<const std::uint8_t>)>;

    /// `serial` may be empty: EM and tip force cells are then counted as serial_frames_without_port.
    explicit DeviceFeeder(hal::CanBus& can, SerialSink serial = {},
                          hal::SimulatedClock* clock = nullptr);
    /// Writes the serial frames with port.device_write.
    DeviceFeeder(hal::CanBus& can, hal::LoopbackSerialPort& port,
                 hal::SimulatedClock* clock = nullptr);

    /// Sends everything `row` carries.
    void feed(const RecordingRow& row);

    [[nodiscard]] const DeviceFeederCounters& counters() const { return counters_; }

private:
    void write_serial(std::span<const std::uint8_t> bytes);

    hal::CanBus& can_;
    SerialSink serial_;
    hal::SimulatedClock* clock_;
    std::uint8_t force_torque_counter_ = 0;
    std::uint8_t insertion_roll_counter_ = 0;
    DeviceFeederCounters counters_{};
};

}  // namespace scopekin::recording
