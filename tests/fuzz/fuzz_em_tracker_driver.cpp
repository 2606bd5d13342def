// fuzz_em_tracker_driver.cpp — libFuzzer target: drivers::EmTrackerDriver
// (firmware/drivers/em_tracker_driver.hpp) on any byte stream, read through a scripted serial
// port (short reads, closed and failed reads, a port that claims more than it gave) or handed to
// receive() directly, with the box's time moving by any step.
//
// Input: a script of operations, each an opcode byte and its operands (missing bytes read as 0):
//   0 raw      n = 1..64 bytes for the port
//   1 pose     a pose frame with a correct CRC for the port, built from 26 operand bytes; opcode
//              bits 3..6 force a known sensor, status 0, a unit quaternion, a position in range
//   2 force    a tip force frame, likewise (bits 3..5: status 0, force in range)
//   3 service  service(port, now + dt); dt = 2 operand bytes (µs) << (opcode bits 3..5)
//   4 receive  receive() of n = 1..512 operand bytes (more than the framer's 256-byte ring)
//   5 port     bit 6: the port's next read is closed (bit 3) or failed, once; bit 4: its reads
//              give at most 1 + operand byte bytes from now on; bit 5: its next full read claims
//              1000 bytes (a backend that overstates: the driver must clamp)
//   6 poll     poll(now + dt)
//   7 take     take_fault_flags(), pop every sample
//
// Oracles (__builtin_trap() on violation, on top of ASan/UBSan):
//   * byte accounting: bytes given to the driver (read by service, whose bytes_read equals what
//     the port gave, at most kMaxBytesPerService, and receive()) == 32 * poses + 17 * forces
//     decoded + bytes_discarded + buffered_bytes(); buffered_bytes() < kEmTrackerMaxFrameSize;
//     no byte is lost, so no buffer overflow is counted;
//   * sample accounting: frames_ok == samples queued (returned by service/receive) ==
//     samples popped + samples_dropped + queued(); queued() <= kSampleQueueCapacity;
//     malformed_payload stays 0;
//   * every counter is non-decreasing; serial_closed / serial_errors count the port's closed and
//     failed reads;
//   * fault flags hold only EmTrackerFault bits; a sample's flags only kEmSampleFaults bits;
//     a flagged sample's flags are counted; a valid pose has a known sensor, |position| <= the
//     limit, a unit quaternion (within the tolerance), status 0; a valid force is in range;
//   * staleness: stale_sources() only monitored sources; a stale source has no valid sample
//     within the timeout; after poll/service every such source is stale; a source whose latest
//     valid sample is from now is not; latest_pose()/latest_tip_force() are valid samples of
//     their own source; kEmFaultStale is set exactly when a source is stale.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <span>
#include <vector>

#include "drivers/em_tracker_driver.hpp"
#include "fuzz_support.hpp"
#include "hal/serial_port.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace {

namespace protocol = scopekin::protocol;
using scopekin::drivers::EmTrackerDriver;
using scopekin::drivers::EmTrackerDriverCounters;
using namespace scopekin::messages;

using scopekin::fuzz::Script;

/// A serial port whose reads the script decides.
class ScriptedPort final : public scopekin::hal::SerialPort {
public:
    scopekin::hal::SerialTransfer read(std::span<std::uint8_t> buffer,
                                       std::uint32_t /*timeout_us*/) override {
        using scopekin::hal::SerialStatus;
        if (next_status != SerialStatus::ok) {
            const SerialStatus status = next_status;
            next_status = SerialStatus::ok;
            ++(status == SerialStatus::closed ? closed : failed);
            return {status, 0};
        }
        if (pending.empty()) return {SerialStatus::timeout, 0};
        std::size_t count = std::min({buffer.size(), pending.size(), max_read});
        std::copy_n(pending.begin(), count, buffer.begin());
        pending.erase(pending.begin(), pending.begin() + static_cast<std::ptrdiff_t>(count));
        given += count;
        if (overclaim) {  // a broken backend: says it gave more than the buffer holds
            overclaim = false;
            return {SerialStatus::ok, count == buffer.size() ? std::size_t{1000} : count};
        }
        return {SerialStatus::ok, count};
    }
    scopekin::hal::SerialTransfer write(std::span<const std::uint8_t> bytes,
                                        std::uint32_t /*timeout_us*/) override {
        return {scopekin::hal::SerialStatus::ok, bytes.size()};
    }
    [[nodiscard]] std::uint32_t baud() const override { return 921600; }
    [[nodiscard]] scopekin::hal::SerialCounters counters() const override { return {}; }

    std::vector<std::uint8_t> pending;
    std::size_t max_read = 4096;
    std::size_t given = 0;
    std::uint64_t closed = 0;
    std::uint64_t failed = 0;
    bool overclaim = false;
    scopekin::hal::SerialStatus next_status = scopekin::hal::SerialStatus::ok;
};

constexpr std::uint32_t kAllEmFaults = (1U << 13U) - 1U;

struct Tally {
    std::uint64_t bytes_in = 0;
    std::uint64_t queued = 0;
    std::uint64_t popped = 0;
    std::uint64_t valid = 0;
    std::uint64_t closed = 0;  ///< closed / failed reads the port returned
    std::uint64_t failed = 0;
    std::uint64_t pose_samples_popped = 0;
    std::uint64_t force_samples_popped = 0;
};

void check_counters_grow(const EmTrackerDriverCounters& before,
                         const EmTrackerDriverCounters& after) {
    require(after.poses_ok >= before.poses_ok && after.tip_forces_ok >= before.tip_forces_ok);
    require(after.unknown_sensor >= before.unknown_sensor);
    require(after.out_of_range >= before.out_of_range);
    require(after.quaternion_norm >= before.quaternion_norm);
    require(after.timestamp_backwards >= before.timestamp_backwards);
    require(after.device_status >= before.device_status);
    require(after.stale_events >= before.stale_events);
    require(after.samples_dropped >= before.samples_dropped);
    require(after.link.frames_ok >= before.link.frames_ok);
    require(after.link.bad_checksum >= before.link.bad_checksum);
    require(after.link.bad_length >= before.link.bad_length);
    require(after.link.unknown_type >= before.link.unknown_type);
    require(after.link.bytes_discarded >= before.link.bytes_discarded);
}

void check_sample(const EmTrackerSample& sample, const EmTrackerDriver& driver) {
    const auto& config = driver.config();
    if (sample.kind == EmTrackerSampleKind::pose) {
        const EmPoseSample& pose = sample.pose;
        require((pose.fault_flags & ~kEmSampleFaults) == 0U);
        require(((pose.fault_flags & kEmFaultUnknownSensor) != 0U) ==
                (pose.sensor_id >= kEmSensorCount));
        require(((pose.fault_flags & kEmFaultDeviceStatus) != 0U) == (pose.device_status != 0U));
        if (pose.fault_flags == 0U) {
            const std::int64_t limit_raw =
                (std::int64_t{config.max_position_um} * 65536 + 999) / 1000 + 1;
            for (const auto& axis : pose.position_mm) {
                require(axis.raw() <= limit_raw && axis.raw() >= -limit_raw);
            }
            std::int64_t norm = 0;  // Q16.16 components = Q2.14 * 4: squares at 2^-32
            for (const auto& component : pose.orientation) {
                norm += std::int64_t{component.raw() / 4} * (component.raw() / 4);
            }
            const std::int64_t deviation =
                norm > (1LL << 28) ? norm - (1LL << 28) : (1LL << 28) - norm;
            require(deviation <=
                    std::int64_t{config.quaternion_norm_squared_tolerance.raw()} * 4096);
        }
    } else {
        const TipForceSample& force = sample.tip_force;
        require((force.fault_flags & ~kEmSampleFaults) == 0U);
        require((force.fault_flags & (kEmFaultUnknownSensor | kEmFaultQuaternionNorm)) == 0U);
        if (force.fault_flags == 0U) {
            const std::int64_t limit_raw =
                (std::int64_t{config.max_force_mN} * 65536 + 999) / 1000 + 1;
            for (const auto& axis : force.force_N) {
                require(axis.raw() <= limit_raw && axis.raw() >= -limit_raw);
            }
            require(force.device_status == 0U);
        }
    }
}

void add_pose(Script& script, std::uint8_t opcode, ScriptedPort& port) {
    protocol::EmPoseMessage message{};
    message.device_time_us = static_cast<std::uint32_t>(script.u16()) << (script.byte() & 15U);
    message.sensor_id = script.byte();
    message.status = script.byte();
    for (auto& axis : message.position_um) {
        axis = static_cast<std::int32_t>(static_cast<std::uint32_t>(script.u16()) |
                                         (static_cast<std::uint32_t>(script.u16()) << 16U));
    }
    for (auto& component : message.orientation_q14) {
        component = static_cast<std::int16_t>(script.u16());
    }
    if ((opcode & 0x08U) != 0U) message.sensor_id &= 3U;
    if ((opcode & 0x10U) != 0U) message.status = 0;
    if ((opcode & 0x20U) != 0U) message.orientation_q14 = {16384, 0, 0, 0};
    if ((opcode & 0x40U) != 0U) {
        for (auto& axis : message.position_um)
            axis %= 1'000'001;
    }
    std::array<std::uint8_t, protocol::kEmTrackerMaxFrameSize> frame{};
    const std::size_t size = protocol::encode_em_pose(message, frame);
    require(size == protocol::kEmTrackerMaxFrameSize);
    port.pending.insert(port.pending.end(), frame.begin(), frame.begin() + size);
}

void add_force(Script& script, std::uint8_t opcode, ScriptedPort& port) {
    protocol::TipForceMessage message{};
    message.device_time_us = static_cast<std::uint32_t>(script.u16()) << (script.byte() & 15U);
    message.status = script.byte();
    for (auto& axis : message.force_mN) {
        axis = static_cast<std::int16_t>(script.u16());
    }
    if ((opcode & 0x08U) != 0U) message.status = 0;
    if ((opcode & 0x10U) != 0U) {
        for (auto& axis : message.force_mN)
            axis = static_cast<std::int16_t>(axis % 25001);
    }
    std::array<std::uint8_t, protocol::kEmTrackerMaxFrameSize> frame{};
    const std::size_t size = protocol::encode_tip_force(message, frame);
    require(size == protocol::kEmTrackerMinFrameSize);
    port.pending.insert(port.pending.end(), frame.begin(), frame.begin() + size);
}

/// The latest valid sample's receive time of each source (poses 0..3, tip force 4), if any.
bool last_valid_us(const EmTrackerDriver& driver, std::size_t source, std::uint64_t& time_us) {
    if (source < kEmSensorCount) {
        const auto sensor = static_cast<EmSensor>(source);
        time_us = driver.latest_pose(sensor).receive_time_us;
        return driver.has_pose(sensor);
    }
    time_us = driver.latest_tip_force().receive_time_us;
    return driver.has_tip_force();
}

void check_state(const EmTrackerDriver& driver, const Tally& tally,
                 const EmTrackerDriverCounters& before, std::uint64_t now_us, bool polled) {
    const EmTrackerDriverCounters c = driver.counters();
    check_counters_grow(before, c);
    require(c.malformed_payload == 0U);
    require(c.link.buffer_overflows == 0U);  // the driver never loses a byte
    require(driver.buffered_bytes() < protocol::kEmTrackerMaxFrameSize);
    // Bytes: in == 32 * poses + 17 * forces + discarded + buffered, poses + forces == frames_ok.
    const std::uint64_t framed = tally.bytes_in - c.link.bytes_discarded - driver.buffered_bytes();
    require(tally.bytes_in >= std::uint64_t{c.link.bytes_discarded} + driver.buffered_bytes());
    require(framed >= 17U * std::uint64_t{c.link.frames_ok});
    require((framed - 17U * std::uint64_t{c.link.frames_ok}) % 15U == 0U);
    const std::uint64_t poses = (framed - 17U * std::uint64_t{c.link.frames_ok}) / 15U;
    require(poses <= c.link.frames_ok && poses >= tally.pose_samples_popped);
    require(c.link.frames_ok - poses >= tally.force_samples_popped);
    require(c.poses_ok <= poses && c.tip_forces_ok <= c.link.frames_ok - poses);
    // Samples: one per frame, popped, dropped or still queued.
    require(c.link.frames_ok == tally.queued);
    require(tally.queued == tally.popped + c.samples_dropped + driver.queued());
    require(driver.queued() <= EmTrackerDriver::kSampleQueueCapacity);
    require(c.serial_closed == tally.closed && c.serial_errors == tally.failed);
    // Flags and staleness.
    const std::uint32_t flags = driver.fault_flags();
    require((flags & ~kAllEmFaults) == 0U);
    const std::uint8_t monitored = driver.config().monitored_sources;
    require((driver.stale_sources() & ~monitored) == 0U);
    require(((flags & kEmFaultStale) != 0U) == (driver.stale_sources() != 0U));
    const std::uint32_t timeout = driver.config().stale_timeout_us;
    for (std::size_t source = 0; source < kEmSourceCount; ++source) {
        const auto bit = static_cast<std::uint8_t>(1U << source);
        if ((monitored & bit) == 0U) continue;
        std::uint64_t last = 0;
        const bool valid = last_valid_us(driver, source, last);
        require(!valid || last <= now_us);
        const bool old = !valid || now_us - last > timeout;
        const bool stale = (driver.stale_sources() & bit) != 0U;
        if (stale) require(old);                       // stale only when it is
        if (polled && old) require(stale);             // and always once polled
        if (valid && last == now_us) require(!stale);  // a sample of now is fresh
    }
    for (std::size_t s = 0; s < kEmSensorCount; ++s) {
        const auto sensor = static_cast<EmSensor>(s);
        if (driver.has_pose(sensor)) {
            require(driver.latest_pose(sensor).fault_flags == 0U);
            require(driver.latest_pose(sensor).sensor_id == s);
        }
    }
    if (driver.has_tip_force()) require(driver.latest_tip_force().fault_flags == 0U);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Script script{data, size};
    EmTrackerDriver driver{};
    ScriptedPort port;
    Tally tally;
    std::uint64_t now_us = 0;

    std::size_t operations = 0;
    while (!script.done() && operations < 512) {  // bound: 512 operations
        ++operations;
        const EmTrackerDriverCounters before = driver.counters();
        const std::uint8_t opcode = script.byte();
        bool polled = false;
        switch (opcode & 7U) {
            case 0: {
                const auto bytes = script.take(1U + (script.byte() & 63U));
                port.pending.insert(port.pending.end(), bytes.begin(), bytes.end());
                break;
            }
            case 1: add_pose(script, opcode, port); break;
            case 2: add_force(script, opcode, port); break;
            case 3: {
                now_us += std::uint64_t{script.u16()} << ((opcode >> 3U) & 7U);
                const std::size_t given_before = port.given;
                const std::size_t pending_before = port.pending.size();
                const auto result = driver.service(port, now_us);
                const std::size_t given = port.given - given_before;
                require(result.bytes_read == given);
                require(result.bytes_read <= EmTrackerDriver::kMaxBytesPerService);
                require(pending_before - port.pending.size() == given);
                tally.bytes_in += given;
                tally.queued += result.samples;
                polled = true;
                break;
            }
            case 4: {
                const auto bytes = script.take(1U + (script.u16() & 511U));
                tally.bytes_in += bytes.size();
                tally.queued += driver.receive(bytes, now_us);
                break;
            }
            case 5: {
                const std::uint8_t operand = script.byte();
                if ((opcode & 0x40U) != 0U && port.next_status == scopekin::hal::SerialStatus::ok) {
                    port.next_status = (opcode & 0x08U) != 0U ? scopekin::hal::SerialStatus::closed
                                                              : scopekin::hal::SerialStatus::failed;
                }
                if ((opcode & 0x10U) != 0U) port.max_read = 1U + operand;
                if ((opcode & 0x20U) != 0U) port.overclaim = true;
                break;
            }
            case 6:
                now_us += std::uint64_t{script.u16()} << ((opcode >> 3U) & 7U);
                driver.poll(now_us);
                polled = true;
                break;
            default: {
                const std::uint32_t flags = driver.take_fault_flags();
                require((flags & ~kAllEmFaults) == 0U);
                require((driver.fault_flags() & ~std::uint32_t{kEmFaultStale}) == 0U);
                EmTrackerSample sample{};
                while (driver.pop(sample)) {  // bound: kSampleQueueCapacity
                    ++tally.popped;
                    ++(sample.kind == EmTrackerSampleKind::pose ? tally.pose_samples_popped
                                                                : tally.force_samples_popped);
                    check_sample(sample, driver);
                }
                break;
            }
        }
        tally.closed = port.closed;
        tally.failed = port.failed;
        check_state(driver, tally, before, now_us, polled);
    }
    return 0;
}
