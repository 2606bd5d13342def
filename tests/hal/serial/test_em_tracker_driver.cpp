// EM tracker driver: conversions to mm / N (Q16.16), validation (unknown sensor, range,
// quaternion norm, timestamps, device status), staleness and recovery, link and serial faults,
// bytes with no sync, bounded reads, queue overflow, a receive() larger than the framer ring (no
// false overflow), and a randomised hostile stream through a
// scripted SerialPort.
// Runs as GoogleTest on x86-64 / aarch64 and with portable_check's runner on Cortex-M4.
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include "drivers/em_tracker_driver.hpp"
#include "em_tracker_sample_match.hpp"
#include "em_tracker_stream.hpp"
#include "em_tracker_test_bytes.hpp"
#include "hal/serial_port.hpp"
#include "portable_check.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace {

using scopekin::drivers::EmTrackerDriver;
using scopekin::drivers::EmTrackerDriverConfig;
using scopekin::fixed_point::Q16_16;
using scopekin::hal::SerialCounters;
using scopekin::hal::SerialPort;
using scopekin::hal::SerialStatus;
using scopekin::hal::SerialTransfer;
using scopekin::messages::EmPoseSample;
using scopekin::messages::EmSensor;
using scopekin::messages::EmTrackerSample;
using scopekin::messages::EmTrackerSampleKind;
using scopekin::messages::TipForceSample;
using scopekin::protocol::EmPoseMessage;
using scopekin::protocol::TipForceMessage;
using Bytes = std::span<const std::uint8_t>;
namespace hal = scopekin::hal;
namespace messages = scopekin::messages;
using scopekin::test::kSpecPose;
using scopekin::test::kSpecTipForce;
using scopekin::test::pose_matches;
using scopekin::test::spec_pose;
using scopekin::test::spec_tip_force;
using scopekin::test::thousandths_to_q16_raw;
using scopekin::test::tip_force_matches;

/// What the test ports below share: reads hand out bytes of a stream, writes fail, no counters.
class StreamSerialPort : public SerialPort {
public:
    SerialTransfer write(std::span<const std::uint8_t>, std::uint32_t) override {
        return {SerialStatus::failed, 0};
    }
    [[nodiscard]] std::uint32_t baud() const override { return 115200U; }
    [[nodiscard]] SerialCounters counters() const override { return {}; }

protected:
    StreamSerialPort() = default;
    ~StreamSerialPort() = default;
    StreamSerialPort(const StreamSerialPort&) = default;
    StreamSerialPort& operator=(const StreamSerialPort&) = default;

    /// Copies the next bytes of `stream` from `offset` (at most `limit`, as many as fit in
    /// `buffer`) and moves `offset` past them.
    static SerialTransfer hand_out(Bytes stream, std::size_t& offset,
                                   std::span<std::uint8_t> buffer, std::size_t limit) {
        std::size_t count = stream.size() - offset;
        count = count < buffer.size() ? count : buffer.size();
        count = count < limit ? count : limit;
        for (std::size_t i = 0; i < count; ++i) {
            buffer[i] = stream[offset + i];
        }
        offset += count;
        return {SerialStatus::ok, count};
    }
};

/// A scripted serial port: hands out queued bytes (at most `max_per_read` per read), then reports
/// `when_empty`.  `lie` makes it claim more bytes than the buffer holds.
class ScriptedSerialPort final : public StreamSerialPort {
public:
    SerialTransfer read(std::span<std::uint8_t> buffer, std::uint32_t) override {
        ++reads;
        if (lie) {
            return {SerialStatus::ok, buffer.size() + 100U};
        }
        if (read_offset == input.size) {
            return {when_empty, 0};
        }
        return hand_out(input.view(), read_offset, buffer, max_per_read);
    }

    scopekin::test::EmTrackerTestBytes<8192> input;
    std::size_t read_offset{0};
    std::size_t max_per_read{std::numeric_limits<std::size_t>::max()};
    SerialStatus when_empty{SerialStatus::timeout};
    bool lie{false};
    std::uint32_t reads{0};
};

// Static storage (the bare-metal stack is 32 KiB; a driver is about 4 KiB, a port 8 KiB).
ScriptedSerialPort g_port;
EmTrackerDriver g_driver;
EmTrackerSample g_sample;

void reset(const EmTrackerDriverConfig& config = {}) {
    g_port = ScriptedSerialPort{};
    g_driver = EmTrackerDriver{config};
    g_sample = EmTrackerSample{};
}

}  // namespace

SCOPEKIN_TEST(EmTrackerDriver, SpecPoseBecomesMillimetresAndUnitQuaternion) {
    reset();
    g_port.input.add_pose(kSpecPose);
    const auto result = g_driver.service(g_port, 5'000'000U);
    SCOPEKIN_EXPECT_TRUE(result.status == SerialStatus::ok);
    SCOPEKIN_EXPECT_EQ(result.bytes_read, 32U);
    SCOPEKIN_EXPECT_EQ(result.samples, 1U);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_TRUE(g_sample.kind == EmTrackerSampleKind::pose);
    const EmPoseSample& sample = g_sample.pose;
    // The spec's numbers (§5): 12.345 mm, -6.789 mm, 250 mm, w = z = 0.70709.
    SCOPEKIN_EXPECT_EQ(sample.position_mm[0].raw(), 809'042);
    SCOPEKIN_EXPECT_EQ(sample.position_mm[1].raw(), -444'924);
    SCOPEKIN_EXPECT_EQ(sample.position_mm[2].raw(), 16'384'000);
    SCOPEKIN_EXPECT_EQ(sample.orientation[0].raw(), 46'340);
    SCOPEKIN_EXPECT_EQ(sample.orientation[1].raw(), 0);
    SCOPEKIN_EXPECT_EQ(sample.orientation[2].raw(), 0);
    SCOPEKIN_EXPECT_EQ(sample.orientation[3].raw(), 46'340);
    SCOPEKIN_EXPECT_EQ(sample.device_time_us, 1'000'000U);
    SCOPEKIN_EXPECT_EQ(sample.receive_time_us, 5'000'000U);
    SCOPEKIN_EXPECT_EQ(sample.fault_flags, 0U);
    SCOPEKIN_EXPECT_TRUE(pose_matches(sample, kSpecPose));
    SCOPEKIN_EXPECT_TRUE(!g_driver.pop(g_sample));

    SCOPEKIN_EXPECT_TRUE(g_driver.has_pose(EmSensor::tip));
    SCOPEKIN_EXPECT_TRUE(!g_driver.has_pose(EmSensor::handle));
    SCOPEKIN_EXPECT_TRUE(pose_matches(g_driver.latest_pose(EmSensor::tip), kSpecPose));
    SCOPEKIN_EXPECT_EQ(g_driver.counters().poses_ok, 1U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().link.frames_ok, 1U);
    // Only the tip has reported: everything else is still stale (missing data is a fault).
    SCOPEKIN_EXPECT_TRUE(!g_driver.stale(EmSensor::tip));
    SCOPEKIN_EXPECT_TRUE(g_driver.stale(EmSensor::twenty_cm));
    SCOPEKIN_EXPECT_TRUE(g_driver.tip_force_stale());
    SCOPEKIN_EXPECT_EQ(g_driver.stale_sources(), 0x1EU);
    SCOPEKIN_EXPECT_EQ(g_driver.fault_flags(), std::uint32_t{messages::kEmFaultStale});
}

SCOPEKIN_TEST(EmTrackerDriver, SpecTipForceBecomesNewtons) {
    reset();
    g_port.input.add_tip_force(kSpecTipForce);
    (void)g_driver.service(g_port, 7U);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_TRUE(g_sample.kind == EmTrackerSampleKind::tip_force);
    // -0.150 N = -9830.4 -> -9830; 0.040 N = 2621.44 -> 2621; 2.5 N = 163840.
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.force_N[0].raw(), -9'830);
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.force_N[1].raw(), 2'621);
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.force_N[2].raw(), 163'840);
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.receive_time_us, 7U);
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.fault_flags, 0U);
    SCOPEKIN_EXPECT_TRUE(g_driver.has_tip_force());
    SCOPEKIN_EXPECT_TRUE(!g_driver.tip_force_stale());
    SCOPEKIN_EXPECT_TRUE(tip_force_matches(g_driver.latest_tip_force(), kSpecTipForce));
    SCOPEKIN_EXPECT_EQ(g_driver.counters().tip_forces_ok, 1U);
    // Extremes of the wire convert without saturating: ±32.767 N.
    TipForceMessage extreme = spec_tip_force(2'000'000U);
    extreme.force_mN = {std::numeric_limits<std::int16_t>::min(),
                        std::numeric_limits<std::int16_t>::max(), 0};
    g_port.input.add_tip_force(extreme);
    (void)g_driver.service(g_port, 8U);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.force_N[0].raw(), thousandths_to_q16_raw(-32768));
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.force_N[1].raw(), thousandths_to_q16_raw(32767));
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.fault_flags, std::uint32_t{messages::kEmFaultOutOfRange});
}

SCOPEKIN_TEST(EmTrackerDriver, UnknownSensorIsFlaggedCountedAndTouchesNoSensor) {
    reset();
    g_port.input.add_pose(spec_pose(4U, 10U));
    g_port.input.add_pose(spec_pose(255U, 11U));
    (void)g_driver.service(g_port, 1U);
    for (int i = 0; i < 2; ++i) {
        SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
        SCOPEKIN_EXPECT_EQ(g_sample.pose.fault_flags,
                           std::uint32_t{messages::kEmFaultUnknownSensor});
    }
    SCOPEKIN_EXPECT_EQ(g_driver.counters().unknown_sensor, 2U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().poses_ok, 0U);
    SCOPEKIN_EXPECT_EQ(g_driver.stale_sources(), 0x1FU);
    SCOPEKIN_EXPECT_TRUE(!g_driver.has_pose(EmSensor::tip));
    SCOPEKIN_EXPECT_TRUE((g_driver.take_fault_flags() & messages::kEmFaultUnknownSensor) != 0U);
}

SCOPEKIN_TEST(EmTrackerDriver, PositionRangeIsChecked) {
    reset();
    EmPoseMessage edge = spec_pose(1U, 100U);
    edge.position_um = {1'000'000, -1'000'000, 0};  // exactly the limit: accepted
    EmPoseMessage beyond = spec_pose(1U, 200U);
    beyond.position_um = {0, 1'000'001, 0};
    EmPoseMessage extreme = spec_pose(1U, 300U);
    extreme.position_um = {std::numeric_limits<std::int32_t>::min(),
                           std::numeric_limits<std::int32_t>::max(), 0};
    g_port.input.add_pose(edge);
    g_port.input.add_pose(beyond);
    g_port.input.add_pose(extreme);
    (void)g_driver.service(g_port, 1U);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.pose.fault_flags, 0U);
    SCOPEKIN_EXPECT_EQ(g_sample.pose.position_mm[0].raw(), 1000 * 65536);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.pose.fault_flags, std::uint32_t{messages::kEmFaultOutOfRange});
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.pose.fault_flags, std::uint32_t{messages::kEmFaultOutOfRange});
    // ±2147 m saturates to the Q16.16 limits: defined, flagged, never wraps.
    SCOPEKIN_EXPECT_TRUE(g_sample.pose.position_mm[0] == Q16_16::min());
    SCOPEKIN_EXPECT_TRUE(g_sample.pose.position_mm[1] == Q16_16::max());
    SCOPEKIN_EXPECT_EQ(g_driver.counters().out_of_range, 2U);
    // The latest valid pose is the one at the limit.
    SCOPEKIN_EXPECT_EQ(g_driver.latest_pose(EmSensor::twenty_cm).device_time_us, 100U);
}

SCOPEKIN_TEST(EmTrackerDriver, QuaternionMustBeUnit) {
    reset();
    const std::array<std::array<std::int16_t, 4>, 6> quaternions{{
        {16384, 0, 0, 0},      // unit
        {-16384, 0, 0, 0},     // -q, the same rotation
        {16384, 16384, 0, 0},  // norm² 2
        {0, 0, 0, 0},          // zero
        {16220, 0, 0, 0},      // norm² 0.980 (deviation 0.0199): inside 1 ± 0.02
        {16200, 0, 0, 0},      // norm² 0.978: outside
    }};
    const std::uint32_t expected[] = {0U,
                                      0U,
                                      messages::kEmFaultQuaternionNorm,
                                      messages::kEmFaultQuaternionNorm,
                                      0U,
                                      messages::kEmFaultQuaternionNorm};
    for (std::size_t i = 0; i < quaternions.size(); ++i) {
        EmPoseMessage message = spec_pose(2U, static_cast<std::uint32_t>(100U + i));
        message.orientation_q14 = quaternions[i];
        g_port.input.add_pose(message);
    }
    (void)g_driver.service(g_port, 1U);
    for (std::size_t i = 0; i < quaternions.size(); ++i) {
        SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
        SCOPEKIN_EXPECT_EQ(g_sample.pose.fault_flags, expected[i]);
    }
    SCOPEKIN_EXPECT_EQ(g_driver.counters().quaternion_norm, 3U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().poses_ok, 3U);
}

SCOPEKIN_TEST(EmTrackerDriver, DeviceTimeMustIncreaseModuloTheWrap) {
    reset();
    const std::uint32_t times[] = {
        0xFFFF'FF00U,  // first: accepted
        0x0000'0100U,  // across the 2^32 wrap: forward
        0x0000'0100U,  // repeated: flagged
        0x0000'0080U,  // backwards: flagged (becomes the reference)
        0x0000'0090U,  // forward again from the new reference
    };
    const std::uint32_t expected[] = {0U, 0U, messages::kEmFaultTimestamp,
                                      messages::kEmFaultTimestamp, 0U};
    for (const std::uint32_t time : times) {
        g_port.input.add_pose(spec_pose(3U, time));
    }
    // Sensors are independent: the tip's clock does not constrain the sigmoid's.
    g_port.input.add_pose(spec_pose(0U, 5U));
    // The tip force has its own reference too.
    g_port.input.add_tip_force(spec_tip_force(50U));
    g_port.input.add_tip_force(spec_tip_force(40U));
    (void)g_driver.service(g_port, 1U);
    for (const std::uint32_t flags : expected) {
        SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
        SCOPEKIN_EXPECT_EQ(g_sample.pose.fault_flags, flags);
    }
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.pose.fault_flags, 0U);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.fault_flags, 0U);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.fault_flags, std::uint32_t{messages::kEmFaultTimestamp});
    SCOPEKIN_EXPECT_EQ(g_driver.counters().timestamp_backwards, 3U);
    SCOPEKIN_EXPECT_EQ(g_driver.latest_pose(EmSensor::sigmoid).device_time_us, 0x90U);
}

SCOPEKIN_TEST(EmTrackerDriver, DeviceStatusIsFlagged) {
    reset();
    EmPoseMessage out_of_box = spec_pose(0U, 1U);
    out_of_box.status = scopekin::protocol::kEmStatusOutOfMotionBox;
    TipForceMessage saturated = spec_tip_force(1U);
    saturated.status = scopekin::protocol::kTipForceStatusSaturated;
    g_port.input.add_pose(out_of_box);
    g_port.input.add_tip_force(saturated);
    (void)g_driver.service(g_port, 1U);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.pose.fault_flags, std::uint32_t{messages::kEmFaultDeviceStatus});
    SCOPEKIN_EXPECT_EQ(g_sample.pose.device_status, 1U);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.tip_force.fault_flags,
                       std::uint32_t{messages::kEmFaultDeviceStatus});
    SCOPEKIN_EXPECT_EQ(g_driver.counters().device_status, 2U);
    SCOPEKIN_EXPECT_TRUE(g_driver.stale(EmSensor::tip));  // a flagged sample does not refresh
    SCOPEKIN_EXPECT_TRUE(g_driver.tip_force_stale());
}

SCOPEKIN_TEST(EmTrackerDriver, StalenessAfterTimeoutAndRecovery) {
    EmTrackerDriverConfig config;
    config.stale_timeout_us = 100'000U;
    reset(config);
    g_port.input.add_pose(spec_pose(0U, 1U));
    (void)g_driver.service(g_port, 1'000'000U);
    SCOPEKIN_EXPECT_TRUE(!g_driver.stale(EmSensor::tip));
    g_driver.poll(1'100'000U);  // exactly the timeout: still fresh
    SCOPEKIN_EXPECT_TRUE(!g_driver.stale(EmSensor::tip));
    g_driver.poll(1'100'001U);
    SCOPEKIN_EXPECT_TRUE(g_driver.stale(EmSensor::tip));
    SCOPEKIN_EXPECT_EQ(g_driver.counters().stale_events, 1U);
    g_driver.poll(1'200'000U);  // still stale: one event, not one per poll
    SCOPEKIN_EXPECT_EQ(g_driver.counters().stale_events, 1U);
    // A flagged sample does not bring it back ...
    EmPoseMessage bad = spec_pose(0U, 2U);
    bad.position_um[0] = 2'000'000;
    g_port.input.add_pose(bad);
    (void)g_driver.service(g_port, 1'250'000U);
    SCOPEKIN_EXPECT_TRUE(g_driver.stale(EmSensor::tip));
    // ... a valid one does, at once.
    g_port.input.add_pose(spec_pose(0U, 3U));
    (void)g_driver.service(g_port, 1'300'000U);
    SCOPEKIN_EXPECT_TRUE(!g_driver.stale(EmSensor::tip));
    SCOPEKIN_EXPECT_EQ(g_driver.latest_pose(EmSensor::tip).receive_time_us, 1'300'000U);
    // A caller clock behind the last reception is "no time elapsed".
    g_driver.poll(0U);
    SCOPEKIN_EXPECT_TRUE(!g_driver.stale(EmSensor::tip));
    // service() polls too: nothing arrives for 100.001 ms.
    (void)g_driver.service(g_port, 1'400'001U);
    SCOPEKIN_EXPECT_TRUE(g_driver.stale(EmSensor::tip));
    SCOPEKIN_EXPECT_EQ(g_driver.counters().stale_events, 2U);
}

namespace {

/// Simulated time (the loopback backend's idea, minimal).
class SteppedClock final : public scopekin::hal::MonotonicClock {
public:
    [[nodiscard]] std::uint64_t now_us() const override { return time_us; }
    void wait_until_us(std::uint64_t deadline_us) override {
        time_us = deadline_us > time_us ? deadline_us : time_us;
    }
    std::uint64_t time_us{0};
};

SteppedClock g_clock;

}  // namespace

SCOPEKIN_TEST(EmTrackerDriver, ServiceWithTheHalClockStampsItsTime) {
    reset();
    g_clock.time_us = 42'000'000U;
    g_port.input.add_pose(spec_pose(2U, 1U));
    (void)g_driver.service(g_port, g_clock);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.pose.receive_time_us, 42'000'000U);
    g_clock.wait_until_us(42'100'001U);  // 100.001 ms without a sample
    (void)g_driver.service(g_port, g_clock);
    SCOPEKIN_EXPECT_TRUE(g_driver.stale(EmSensor::handle));
}

SCOPEKIN_TEST(EmTrackerDriver, OnlyMonitoredSourcesGoStale) {
    EmTrackerDriverConfig config;
    config.monitored_sources = messages::kEmSourceTip | messages::kEmSourceTipForce;
    reset(config);
    SCOPEKIN_EXPECT_EQ(g_driver.stale_sources(), 0x11U);
    g_port.input.add_pose(spec_pose(0U, 1U));
    g_port.input.add_pose(spec_pose(2U, 1U));  // the handle sends although not monitored: accepted
    g_port.input.add_tip_force(spec_tip_force(1U));
    (void)g_driver.service(g_port, 0U);
    SCOPEKIN_EXPECT_EQ(g_driver.stale_sources(), 0U);
    SCOPEKIN_EXPECT_EQ(g_driver.fault_flags(), 0U);
    g_driver.poll(10'000'000U);
    SCOPEKIN_EXPECT_EQ(g_driver.stale_sources(), 0x11U);  // the handle is not monitored
    SCOPEKIN_EXPECT_TRUE(!g_driver.stale(EmSensor::handle));
    SCOPEKIN_EXPECT_EQ(g_driver.counters().stale_events, 2U);
}

SCOPEKIN_TEST(EmTrackerDriver, LinkFaultsAreFlaggedUntilTaken) {
    reset();
    std::array<std::uint8_t, 32> frame{};
    (void)scopekin::protocol::encode_em_pose(kSpecPose, frame);
    frame[20] = static_cast<std::uint8_t>(frame[20] ^ 0x10U);  // bad checksum
    g_port.input.add(frame);
    const std::array<std::uint8_t, 4> bad_length{0xA5, 0x5A, 0x02, 0xFF};
    const std::array<std::uint8_t, 4> unknown_type{0xA5, 0x5A, 0x33, 0x00};
    g_port.input.add(bad_length);
    g_port.input.add(unknown_type);
    g_port.input.add_pose(spec_pose(0U, 1U));
    (void)g_driver.service(g_port, 0U);
    const std::uint32_t flags = g_driver.take_fault_flags();
    SCOPEKIN_EXPECT_TRUE((flags & messages::kEmFaultBadChecksum) != 0U);
    SCOPEKIN_EXPECT_TRUE((flags & messages::kEmFaultBadLength) != 0U);
    SCOPEKIN_EXPECT_TRUE((flags & messages::kEmFaultUnknownType) != 0U);
    SCOPEKIN_EXPECT_TRUE((flags & messages::kEmFaultStale) != 0U);  // 3 sensors + force never sent
    SCOPEKIN_EXPECT_TRUE((flags & messages::kEmFaultSerial) == 0U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().link.bad_checksum, 1U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().link.bad_length, 1U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().link.unknown_type, 1U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().link.frames_ok, 1U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().poses_ok, 1U);
    // Taken: the events are gone, the stale condition is not.
    SCOPEKIN_EXPECT_EQ(g_driver.fault_flags(), std::uint32_t{messages::kEmFaultStale});
}

// Bytes that never start a frame (no sync byte at all) are discarded and flagged as such in the
// call that saw them: a line of noise is a framing fault at once, not only a stale sensor later.
SCOPEKIN_TEST(EmTrackerDriver, BytesWithNoSyncAreFlagged) {
    reset();
    std::array<std::uint8_t, 100> noise{};
    for (std::size_t i = 0; i < noise.size(); ++i) {
        noise[i] = static_cast<std::uint8_t>((i * 37U) & 0x7FU);  // never 0xA5
    }
    g_port.input.add(noise);
    (void)g_driver.service(g_port, 0U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().link.bytes_discarded, 100U);
    std::uint32_t flags = g_driver.take_fault_flags();
    SCOPEKIN_EXPECT_TRUE((flags & messages::kEmFaultNoSync) != 0U);
    SCOPEKIN_EXPECT_EQ(flags & (messages::kEmFaultBadChecksum | messages::kEmFaultBadLength |
                                messages::kEmFaultUnknownType),
                       0U);  // no candidate frame at all
    // A clean frame next: nothing discarded, no flag.
    g_port.input.add_pose(spec_pose(0U, 1U));
    (void)g_driver.service(g_port, 1U);
    flags = g_driver.take_fault_flags();
    SCOPEKIN_EXPECT_EQ(flags & messages::kEmFaultNoSync, 0U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().link.frames_ok, 1U);
}

SCOPEKIN_TEST(EmTrackerDriver, SerialClosedAndFailedAreCountedAndFlagged) {
    reset();
    g_port.input.add_pose(spec_pose(0U, 1U));
    g_port.when_empty = SerialStatus::closed;
    auto result = g_driver.service(g_port, 0U);
    SCOPEKIN_EXPECT_TRUE(result.status == SerialStatus::ok);  // a short read ends the call
    SCOPEKIN_EXPECT_EQ(result.samples, 1U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().serial_closed, 0U);
    result = g_driver.service(g_port, 1U);
    SCOPEKIN_EXPECT_TRUE(result.status == SerialStatus::closed);
    SCOPEKIN_EXPECT_EQ(result.bytes_read, 0U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().serial_closed, 1U);
    SCOPEKIN_EXPECT_TRUE((g_driver.take_fault_flags() & messages::kEmFaultSerial) != 0U);
    g_port.when_empty = SerialStatus::failed;
    result = g_driver.service(g_port, 2U);
    SCOPEKIN_EXPECT_TRUE(result.status == SerialStatus::failed);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().serial_errors, 1U);
    SCOPEKIN_EXPECT_TRUE((g_driver.take_fault_flags() & messages::kEmFaultSerial) != 0U);
    g_port.when_empty = SerialStatus::timeout;
    result = g_driver.service(g_port, 3U);
    SCOPEKIN_EXPECT_TRUE(result.status == SerialStatus::timeout);
    SCOPEKIN_EXPECT_TRUE((g_driver.take_fault_flags() & messages::kEmFaultSerial) == 0U);

    // A full chunk followed by a hang-up: the bytes count, the hang-up too.
    reset();
    static_assert(EmTrackerDriver::kReadChunkBytes == 4U * 32U);
    for (std::uint32_t i = 0; i < 4U; ++i) {
        g_port.input.add_pose(spec_pose(0U, 10U + i));  // 128 bytes: exactly one chunk
    }
    g_port.when_empty = SerialStatus::closed;
    result = g_driver.service(g_port, 0U);
    SCOPEKIN_EXPECT_TRUE(result.status == SerialStatus::ok);
    SCOPEKIN_EXPECT_EQ(result.samples, 4U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().serial_closed, 1U);
}

SCOPEKIN_TEST(EmTrackerDriver, ServiceReadsABoundedNumberOfBytes) {
    reset();
    for (std::uint32_t i = 0; i < 40U; ++i) {  // 40 poses = 1280 bytes waiting
        g_port.input.add_pose(spec_pose(static_cast<std::uint8_t>(i % 4U), 100U + i));
    }
    const auto first = g_driver.service(g_port, 0U);
    constexpr std::size_t per_call =
        EmTrackerDriver::kReadChunkBytes * EmTrackerDriver::kReadsPerService;
    SCOPEKIN_EXPECT_EQ(first.bytes_read, per_call);
    SCOPEKIN_EXPECT_EQ(g_port.reads, EmTrackerDriver::kReadsPerService);
    SCOPEKIN_EXPECT_EQ(first.samples, 32U);  // 1024 bytes = 32 poses exactly
    std::size_t samples = first.samples;
    for (int call = 0; call < 10; ++call) {
        samples += g_driver.service(g_port, 0U).samples;
        while (g_driver.pop(g_sample)) {
        }
    }
    SCOPEKIN_EXPECT_EQ(samples, 40U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().poses_ok, 40U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().samples_dropped, 0U);

    // A port that trickles 5 bytes per read stops the service call at its first short read.
    reset();
    g_port.input.add_pose(spec_pose(0U, 1U));
    g_port.max_per_read = 5U;
    SCOPEKIN_EXPECT_EQ(g_driver.service(g_port, 0U).bytes_read, 5U);

    // A port that claims more bytes than the buffer holds is clamped, not trusted.
    reset();
    g_port.lie = true;
    SCOPEKIN_EXPECT_EQ(g_driver.service(g_port, 0U).bytes_read, per_call);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().link.frames_ok, 0U);
}

SCOPEKIN_TEST(EmTrackerDriver, QueueOverflowDropsTheOldest) {
    reset();
    static std::array<std::uint8_t, 80 * 32> stream{};
    std::size_t size = 0;
    for (std::uint32_t i = 0; i < 80U; ++i) {
        size += scopekin::protocol::encode_em_pose(spec_pose(1U, 1000U + i),
                                                   std::span<std::uint8_t>{stream}.subspan(size));
    }
    SCOPEKIN_EXPECT_EQ(g_driver.receive(Bytes{stream.data(), size}, 0U), 80U);
    SCOPEKIN_EXPECT_EQ(g_driver.queued(), EmTrackerDriver::kSampleQueueCapacity);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().samples_dropped,
                       80U - EmTrackerDriver::kSampleQueueCapacity);
    SCOPEKIN_EXPECT_TRUE((g_driver.fault_flags() & messages::kEmFaultQueueOverflow) != 0U);
    SCOPEKIN_EXPECT_TRUE(g_driver.pop(g_sample));
    SCOPEKIN_EXPECT_EQ(g_sample.pose.device_time_us,
                       1000U + 80U - EmTrackerDriver::kSampleQueueCapacity);
    // The latest value is the newest sample, whatever the queue dropped.
    SCOPEKIN_EXPECT_EQ(g_driver.latest_pose(EmSensor::twenty_cm).device_time_us, 1079U);
}

SCOPEKIN_TEST(EmTrackerDriver, AReceiveLargerThanTheRingLosesNothingAndFlagsNoOverflow) {
    reset();
    // 20 poses, 640 bytes in one receive(): more than the framer's 256-byte ring takes at once.
    static std::array<std::uint8_t, 20 * 32> stream{};
    std::size_t size = 0;
    for (std::uint32_t i = 0; i < 20U; ++i) {
        size += scopekin::protocol::encode_em_pose(spec_pose(2U, 500U + i),
                                                   std::span<std::uint8_t>{stream}.subspan(size));
    }
    SCOPEKIN_EXPECT_EQ(g_driver.receive(Bytes{stream.data(), size}, 0U), 20U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().link.frames_ok, 20U);
    SCOPEKIN_EXPECT_EQ(g_driver.counters().link.buffer_overflows, 0U);
    SCOPEKIN_EXPECT_EQ(g_driver.take_fault_flags() & messages::kEmFaultBufferOverflow, 0U);
}

// --- Randomised hostile stream through a scripted port --------------------------------------------

namespace {

constexpr std::size_t kDriverStressEvents = 3000;
std::array<std::uint8_t, kDriverStressEvents * 32> g_driver_stream{};
std::array<scopekin::test::ExpectedEmMessage, kDriverStressEvents> g_driver_expected{};

/// A port over a long stream that hands out random-sized pieces (1..80 bytes per read).
class TricklingSerialPort final : public StreamSerialPort {
public:
    TricklingSerialPort(Bytes stream, std::uint32_t seed) : stream_(stream), prng_(seed) {}
    SerialTransfer read(std::span<std::uint8_t> buffer, std::uint32_t) override {
        if (offset_ == stream_.size()) {
            return {SerialStatus::timeout, 0};
        }
        return hand_out(stream_, offset_, buffer, 1U + prng_.below(80U));
    }
    [[nodiscard]] bool done() const { return offset_ == stream_.size(); }

private:
    Bytes stream_;
    std::size_t offset_{0};
    scopekin::test::TestPrng prng_;
};

}  // namespace

SCOPEKIN_TEST(EmTrackerDriver, RandomisedStreamYieldsExactlyTheValidSamples) {
    scopekin::test::EmTrackerStreamGenerator generator(0xE17AC0DEU);
    std::size_t expected_count = 0;
    const std::size_t size = scopekin::test::generate_em_tracker_stream(
        generator, g_driver_stream, g_driver_expected, kDriverStressEvents, expected_count);
    TricklingSerialPort port(Bytes{g_driver_stream.data(), size}, 77U);
    reset();
    std::size_t matched = 0;
    std::size_t popped = 0;
    std::uint64_t now_us = 0;
    for (std::size_t call = 0; call < size && !port.done(); ++call) {  // >= 1 byte per call
        now_us += 2'000U;
        (void)g_driver.service(port, now_us);
        while (g_driver.pop(g_sample)) {
            if (popped < expected_count) {
                const bool same =
                    scopekin::test::sample_matches(g_sample, g_driver_expected[popped]);
                matched += same ? 1U : 0U;
            }
            ++popped;
        }
    }
    SCOPEKIN_EXPECT_TRUE(port.done());
    SCOPEKIN_EXPECT_EQ(popped, expected_count);
    SCOPEKIN_EXPECT_EQ(matched, expected_count);
    const auto counters = g_driver.counters();
    SCOPEKIN_EXPECT_EQ(counters.poses_ok + counters.tip_forces_ok, expected_count);
    SCOPEKIN_EXPECT_EQ(counters.samples_dropped, 0U);
    SCOPEKIN_EXPECT_EQ(counters.timestamp_backwards, 0U);  // the device clock wrapped on the way
    SCOPEKIN_EXPECT_EQ(counters.malformed_payload, 0U);
    SCOPEKIN_EXPECT_TRUE(counters.link.bad_checksum > 0U);
}
