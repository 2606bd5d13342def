// DeviceFeeder: recording rows -> the box's CAN frames and serial bytes.  The frames decode (with
// the protocol's own decoders) to the row's values at the wire's resolution, and the box-side
// drivers (HandleSensors on a LoopbackCanWire, EmTrackerDriver on a LoopbackSerialPort) take them
// as valid samples.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "drivers/em_tracker_driver.hpp"
#include "drivers/handle_sensors.hpp"
#include "hal/loopback/loopback_can.hpp"
#include "hal/loopback/loopback_serial.hpp"
#include "hal/loopback/simulated_clock.hpp"
#include "host_sim/recording/device_feeder.hpp"
#include "host_sim/recording/wire_values.hpp"
#include "protocol/can/scopekin_messages.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace {

namespace hal = scopekin::hal;
namespace drivers = scopekin::drivers;
namespace messages = scopekin::messages;
namespace protocol = scopekin::protocol;
namespace wire = scopekin::recording::wire;
using scopekin::fixed_point::Q16_16;
using scopekin::recording::DeviceFeeder;
using scopekin::recording::EmPoseCells;
using scopekin::recording::ForceTorqueCells;
using scopekin::recording::InsertionRollCells;
using scopekin::recording::RecordingRow;
using scopekin::recording::TipForceCells;

/// The simulated world's peripherals.  Static storage: the wire holds 2 × 1024 frames.
struct Bench {
    hal::SimulatedClock clock{0};
    hal::LoopbackCanWire wire{clock};
    hal::LoopbackSerialPort serial{115200};
};
Bench bench_decode;
Bench bench_handle_driver;
Bench bench_em_driver;
Bench bench_no_serial;
Bench bench_bus_off;

/// A row with every group, values varying with k (some between wire steps).
RecordingRow full_row(std::int64_t time_us, int k) {
    RecordingRow row;
    row.time_us = time_us;
    const double s = static_cast<double>(k);
    row.handle = ForceTorqueCells{2.0 + 0.0123 * s, -15.0 + 0.37 * s};
    row.insertion_roll = InsertionRollCells{100.0 + 0.0537 * s, -0.5 + 0.00123 * s};
    for (std::size_t slot = 0; slot < 4; ++slot) {
        const double a = 0.1 * s + static_cast<double>(slot);
        row.em[slot] = EmPoseCells{
            {10.0 * static_cast<double>(slot) + 0.0004 * s, -20.5 + s, 300.0 - 0.1234 * s},
            {std::cos(a / 2), 0.0, std::sin(a / 2) * 0.6, std::sin(a / 2) * 0.8}};
    }
    row.tip_force = TipForceCells{{0.0, 0.0, 0.25 + 0.0137 * s}};
    row.region = "sigmoid";
    return row;
}

std::vector<hal::ReceivedCanFrame> drain(hal::LoopbackCanEndpoint& endpoint) {
    std::vector<hal::ReceivedCanFrame> frames;
    hal::ReceivedCanFrame received{};
    while (endpoint.receive(received, 0) == hal::CanStatus::ok)
        frames.push_back(received);
    return frames;
}

std::vector<protocol::EmTrackerFrame> serial_frames(hal::LoopbackSerialPort& port) {
    std::vector<protocol::EmTrackerFrame> frames;
    protocol::EmTrackerFramer framer;
    std::array<std::uint8_t, 64> buffer{};
    while (true) {
        const auto transfer = port.read(buffer, 0);
        if (transfer.count == 0) break;
        EXPECT_EQ(framer.push(std::span<const std::uint8_t>(buffer.data(), transfer.count)),
                  transfer.count);
        protocol::EmTrackerFrame frame{};
        while (framer.pop(frame))
            frames.push_back(frame);
    }
    EXPECT_EQ(framer.counters().bytes_discarded, 0u);
    return frames;
}

TEST(DeviceFeeder, FramesDecodeToTheRowsValuesWithRollingCounters) {
    Bench& b = bench_decode;
    DeviceFeeder feeder(b.wire.world(), b.serial, &b.clock);
    for (int k = 0; k < 20; ++k) {
        const RecordingRow row = full_row(1000 * (k + 1), k);
        const RecordingRow expected = wire::quantize_to_wire(row);
        feeder.feed(row);
        EXPECT_EQ(b.clock.now_us(), static_cast<std::uint64_t>(row.time_us));

        const auto frames = drain(b.wire.box());
        ASSERT_EQ(frames.size(), 2u);
        protocol::HandleForceTorque force{};
        ASSERT_EQ(protocol::decode(frames[0].frame, force), protocol::DecodeResult::ok);
        protocol::InsertionRoll insertion{};
        ASSERT_EQ(protocol::decode(frames[1].frame, insertion), protocol::DecodeResult::ok);
        EXPECT_EQ(frames[0].timestamp_us, static_cast<std::uint64_t>(row.time_us));
        EXPECT_EQ(force.counter, k % 16);
        EXPECT_EQ(insertion.counter, k % 16);
        EXPECT_EQ(force.status, 0);
        EXPECT_EQ(insertion.status, 0);
        // The decoded Q16.16 value is the wire value within half a Q16.16 step.
        const double q = 1.0 / 65536.0;
        EXPECT_NEAR(force.force_N.raw() * q, expected.handle->force_N, q / 2);
        EXPECT_NEAR(force.torque_Nmm.raw() * q, expected.handle->torque_Nmm, q / 2);
        EXPECT_NEAR(insertion.insertion_mm.raw() * q, expected.insertion_roll->insertion_mm, q / 2);
        EXPECT_NEAR(insertion.roll_rad.raw() * q, expected.insertion_roll->roll_rad, q / 2);
        // ... and the raw integers on the wire are round(value / DBC factor) of the row's values.
        EXPECT_EQ(protocol::read_raw(frames[0].frame.data, wire::handle_force_signal()),
                  std::llround(row.handle->force_N * 200.0));
        EXPECT_EQ(protocol::read_raw(frames[1].frame.data, wire::roll_signal()),
                  std::llround(row.insertion_roll->roll_rad * 10000.0));
        EXPECT_EQ(wire::from_message(force), *expected.handle);
        EXPECT_EQ(wire::from_message(insertion), *expected.insertion_roll);

        const auto serial = serial_frames(b.serial);
        ASSERT_EQ(serial.size(), 5u);
        for (std::size_t slot = 0; slot < 4; ++slot) {
            protocol::EmPoseMessage pose{};
            ASSERT_TRUE(protocol::decode_em_pose(serial[slot], pose));
            EXPECT_EQ(pose.sensor_id, slot);
            EXPECT_EQ(pose.status, 0);
            EXPECT_EQ(pose.device_time_us, static_cast<std::uint32_t>(row.time_us));
            for (std::size_t i = 0; i < 3; ++i)
                EXPECT_EQ(pose.position_um[i], std::llround(row.em[slot]->position_mm[i] * 1000.0));
            for (std::size_t i = 0; i < 4; ++i)
                EXPECT_EQ(pose.orientation_q14[i],
                          std::llround(row.em[slot]->quaternion_wxyz[i] * 16384.0));
            EXPECT_EQ(wire::from_message(pose), *expected.em[slot]);
        }
        protocol::TipForceMessage tip{};
        ASSERT_TRUE(protocol::decode_tip_force(serial[4], tip));
        EXPECT_EQ(tip.device_time_us, static_cast<std::uint32_t>(row.time_us));
        EXPECT_EQ(tip.force_mN[2], std::llround(row.tip_force->force_N[2] * 1000.0));
        EXPECT_EQ(wire::from_message(tip), *expected.tip_force);
    }
    const auto& c = feeder.counters();
    EXPECT_EQ(c.rows, 20u);
    EXPECT_EQ(c.handle_force_torque_frames, 20u);
    EXPECT_EQ(c.insertion_roll_frames, 20u);
    EXPECT_EQ(c.em_pose_frames, (std::array<std::uint64_t, 4>{20, 20, 20, 20}));
    EXPECT_EQ(c.tip_force_frames, 20u);
    EXPECT_EQ(c.serial_bytes_written, 20u * (4u * 32u + 17u));
    EXPECT_EQ(c.serial_bytes_lost, 0u);
    EXPECT_EQ(c.can_send_failures, 0u);
}

TEST(DeviceFeeder, HandleSensorsDriverTakesEveryFrameAndSeesDropoutsAsStaleness) {
    Bench& b = bench_handle_driver;
    DeviceFeeder feeder(b.wire.world(), DeviceFeeder::SerialSink{}, &b.clock);
    scopekin::drivers::HandleSensors driver;
    int accepted = 0;
    auto run_ms = [&](int from_ms, int to_ms, bool with_force) {
        for (int ms = from_ms; ms < to_ms; ++ms) {
            RecordingRow row = full_row(1000 * ms, ms);
            if (!with_force) row.handle.reset();
            feeder.feed(row);
            for (const auto& frame : drain(b.wire.box()))
                accepted += driver.accept(frame) ? 1 : 0;
            if (ms % 5 == 4) {
                const messages::HandleSamples samples = driver.take_samples(b.clock.now_us());
                const RecordingRow expected = wire::quantize_to_wire(row);
                EXPECT_EQ(samples.insertion_roll.insertion_mm,
                          wire::to_insertion_roll(*expected.insertion_roll, 0).insertion_mm)
                    << ms;
                EXPECT_EQ(samples.insertion_roll.roll_rad,
                          wire::to_insertion_roll(*expected.insertion_roll, 0).roll_rad)
                    << ms;
                if (with_force) {
                    EXPECT_EQ(samples.force_torque.force_N,
                              wire::to_handle_force_torque(*expected.handle, 0).force_N)
                        << ms;
                    EXPECT_EQ(samples.force_torque.torque_Nmm,
                              wire::to_handle_force_torque(*expected.handle, 0).torque_Nmm)
                        << ms;
                }
            }
        }
    };
    run_ms(0, 200, true);
    EXPECT_EQ(accepted, 400);
    EXPECT_EQ(driver.counters().force_torque_samples, 200u);
    EXPECT_EQ(driver.counters().insertion_roll_samples, 200u);
    EXPECT_EQ(driver.counters().counter_gaps, 0u);
    EXPECT_EQ(driver.counters().sensor_status, 0u);
    EXPECT_EQ(driver.counters().stale_events, 0u);
    EXPECT_EQ(driver.faults(), 0);

    // 40 ms without force/torque in the recording: stale (15 ms default), never a counter gap.
    run_ms(200, 240, false);
    EXPECT_NE(driver.faults() & scopekin::messages::kBoxFaultForceTorqueStale, 0);
    run_ms(240, 260, true);
    EXPECT_EQ(driver.counters().counter_gaps, 0u);
    EXPECT_EQ(driver.counters().stale_events, 1u);
    EXPECT_EQ(driver.faults(), 0);
    EXPECT_EQ(driver.counters().force_torque_samples, 220u);
    EXPECT_EQ(driver.counters().insertion_roll_samples, 260u);
}

TEST(DeviceFeeder, EmTrackerDriverTakesEveryPoseAndTipForce) {
    Bench& b = bench_em_driver;
    DeviceFeeder feeder(b.wire.world(), b.serial, &b.clock);
    drivers::EmTrackerDriver driver;
    std::uint32_t samples = 0;
    for (int k = 0; k < 60; ++k) {  // 2 s at the bench's 33 ms
        RecordingRow row = full_row(33'000 * k, k);
        row.handle.reset();
        row.insertion_roll.reset();
        feeder.feed(row);
        const auto result = driver.service(b.serial, b.clock);
        samples += result.samples;
        messages::EmTrackerSample sample{};
        while (driver.pop(sample))
            EXPECT_EQ(sample.kind == messages::EmTrackerSampleKind::pose
                          ? sample.pose.fault_flags
                          : sample.tip_force.fault_flags,
                      0u);
        for (std::size_t slot = 0; slot < 4; ++slot) {
            const auto sensor = static_cast<messages::EmSensor>(slot);
            ASSERT_TRUE(driver.has_pose(sensor));
            const auto& pose = driver.latest_pose(sensor);
            for (std::size_t i = 0; i < 3; ++i)
                EXPECT_EQ(pose.position_mm[i],
                          Q16_16::from_ratio(static_cast<std::int32_t>(std::llround(
                                                 row.em[slot]->position_mm[i] * 1000.0)),
                                             1000));
            for (std::size_t i = 0; i < 4; ++i)
                EXPECT_EQ(pose.orientation[i].raw(),
                          4 * std::llround(row.em[slot]->quaternion_wxyz[i] * 16384.0));
            EXPECT_EQ(pose.device_time_us, static_cast<std::uint32_t>(row.time_us));
            EXPECT_EQ(pose.receive_time_us, static_cast<std::uint64_t>(row.time_us));
        }
        ASSERT_TRUE(driver.has_tip_force());
        EXPECT_EQ(
            driver.latest_tip_force().force_N[2],
            Q16_16::from_ratio(
                static_cast<std::int32_t>(std::llround(row.tip_force->force_N[2] * 1000.0)), 1000));
        EXPECT_EQ(driver.stale_sources(), 0);
        EXPECT_EQ(driver.take_fault_flags(), 0u);
    }
    EXPECT_EQ(samples, 300u);
    const auto counters = driver.counters();
    EXPECT_EQ(counters.poses_ok, 240u);
    EXPECT_EQ(counters.tip_forces_ok, 60u);
    EXPECT_EQ(counters.link.bad_checksum, 0u);
    EXPECT_EQ(counters.link.bytes_discarded, 0u);
    EXPECT_EQ(counters.timestamp_backwards, 0u);
    EXPECT_EQ(counters.quaternion_norm, 0u);
}

TEST(DeviceFeeder, WithoutASerialPortEmCellsAreCountedNotSent) {
    Bench& b = bench_no_serial;
    DeviceFeeder feeder(b.wire.world());
    b.clock.advance_to(5000);
    feeder.feed(full_row(5000, 1));
    EXPECT_EQ(feeder.counters().serial_frames_without_port, 5u);
    EXPECT_EQ(feeder.counters().handle_force_torque_frames, 1u);
    EXPECT_EQ(drain(b.wire.box()).size(), 2u);
}

TEST(DeviceFeeder, ACounterAdvancesOnlyForFramesSent) {
    Bench& b = bench_bus_off;
    DeviceFeeder feeder(b.wire.world(), DeviceFeeder::SerialSink{}, &b.clock);
    RecordingRow row;
    row.handle = ForceTorqueCells{1.0, 0.0};
    row.time_us = 1000;
    feeder.feed(row);  // counter 0
    b.wire.world().set_bus_off(true);
    row.time_us = 2000;
    feeder.feed(row);  // refused
    b.wire.world().set_bus_off(false);
    row.time_us = 3000;
    feeder.feed(row);  // counter 1
    const auto frames = drain(b.wire.box());
    ASSERT_EQ(frames.size(), 2u);
    protocol::HandleForceTorque message{};
    ASSERT_EQ(protocol::decode(frames[1].frame, message), protocol::DecodeResult::ok);
    EXPECT_EQ(message.counter, 1);
    EXPECT_EQ(frames[1].timestamp_us, 3000u);
    EXPECT_EQ(feeder.counters().can_send_failures, 1u);
    EXPECT_EQ(feeder.counters().handle_force_torque_frames, 2u);
}

}  // namespace
