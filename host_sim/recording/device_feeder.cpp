#include "host_sim/recording/device_feeder.hpp"

#include <array>

#include "host_sim/recording/wire_values.hpp"
#include "protocol/can/scopekin_messages.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace scopekin::recording {

namespace {
constexpr std::uint8_t kCounterModulo = 16;  // 4-bit rolling counters (scopekin.dbc)
}  // namespace

DeviceFeeder::DeviceFeeder(hal::CanBus& can, SerialSink serial, hal::SimulatedClock* clock)
    : can_(can), serial_(std::move(serial)), clock_(clock) {}

DeviceFeeder::DeviceFeeder(hal::CanBus& can, hal::LoopbackSerialPort& port,
                           hal::SimulatedClock* clock)
    : DeviceFeeder(
          can, [&port](std::span<const std::uint8_t> bytes) { return port.device_write(bytes); },
          clock) {}

void DeviceFeeder::write_serial(std::span<const std::uint8_t> bytes) {
    const std::size_t written = serial_(bytes);
    counters_.serial_bytes_written += written;
    counters_.serial_bytes_lost += bytes.size() - (written < bytes.size() ? written : bytes.size());
}

void DeviceFeeder::feed(const RecordingRow& row) {
    ++counters_.rows;
    if (clock_ != nullptr && row.time_us >= 0)
        clock_->advance_to(static_cast<std::uint64_t>(row.time_us));

    if (row.handle) {
        const hal::CanFrame frame =
            protocol::encode(wire::to_handle_force_torque(*row.handle, force_torque_counter_));
        if (can_.send(frame, 0) == hal::CanStatus::ok) {
            ++counters_.handle_force_torque_frames;
            force_torque_counter_ =
                static_cast<std::uint8_t>((force_torque_counter_ + 1U) % kCounterModulo);
        } else {
            ++counters_.can_send_failures;
        }
    }
    if (row.insertion_roll) {
        const hal::CanFrame frame =
            protocol::encode(wire::to_insertion_roll(*row.insertion_roll, insertion_roll_counter_));
        if (can_.send(frame, 0) == hal::CanStatus::ok) {
            ++counters_.insertion_roll_frames;
            insertion_roll_counter_ =
                static_cast<std::uint8_t>((insertion_roll_counter_ + 1U) % kCounterModulo);
        } else {
            ++counters_.can_send_failures;
        }
    }

    // The tracker clock is 32 bits of µs: it wraps every 71.6 min (em_tracker_serial.md §3).
    const auto device_time_us =
        static_cast<std::uint32_t>(static_cast<std::uint64_t>(row.time_us) & 0xFFFFFFFFU);
    std::array<std::uint8_t, protocol::kEmTrackerMaxFrameSize> buffer{};
    for (std::size_t slot = 0; slot < kEmSlotCount; ++slot) {
        if (!row.em[slot]) continue;
        if (!serial_) {
            ++counters_.serial_frames_without_port;
            continue;
        }
        const std::size_t size = protocol::encode_em_pose(
            wire::to_em_pose(*row.em[slot], static_cast<std::uint8_t>(slot), device_time_us),
            buffer);
        write_serial(std::span<const std::uint8_t>(buffer.data(), size));
        ++counters_.em_pose_frames[slot];
    }
    if (row.tip_force) {
        if (!serial_) {
            ++counters_.serial_frames_without_port;
        } else {
            const std::size_t size = protocol::encode_tip_force(
                wire::to_tip_force(*row.tip_force, device_time_us), buffer);
            write_serial(std::span<const std::uint8_t>(buffer.data(), size));
            ++counters_.tip_force_frames;
        }
    }
}

}  // namespace scopekin::recording
