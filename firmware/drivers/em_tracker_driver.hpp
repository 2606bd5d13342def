// em_tracker_driver.hpp — the test bench's EM tracker and tip force sensor, as typed samples.
//
// Reads the serial byte stream of firmware/protocol/em_tracker/em_tracker_serial.md from a
// hal::SerialPort (a bounded number of bytes per call, never waiting), frames it, and turns every
// valid frame into a validated, time-stamped sample with fault flags:
//   * EmPoseSample   — one tracker sensor's position (mm, Q16.16) and orientation (unit
//                      quaternion, Q16.16), device time, receive time;
//   * TipForceSample — tip contact force (N, Q16.16).
// Validation per sample: unknown sensor id, position/force out of range, quaternion not unit,
// device time not increasing, device status.  Per source (4 sensors + tip force): staleness
// (no valid sample within a timeout).  Link level (from the framer): bad checksum, bad length,
// unknown message type, buffer overflow, bytes discarded while looking for a frame start (noise,
// a line with no sync); serial port closed/failed.  Every fault kind has a bit
// flag (EmTrackerFault) and a counter (EmTrackerDriverCounters).  The spec's §4 lists the degraded
// behaviour of each.
//
// Fixed-point conversions (Q16.16 = fixed_point::Q16_16, raw = round(value * 2^16)):
//   position: µm (int32) -> mm: Q16_16::from_ratio(um, 1000), i.e. round(um * 2^16 / 1000),
//     rounded half away from zero, exact intermediate (|um| * 2^16 < 2^47 in int64).  Saturates at
//     ±32767.99 mm, which only an out-of-range (flagged) sample can reach: valid ones are within
//     ±1000 mm.  Resolution 15 nm, far below the wire's 1 µm.
//   orientation: Q2.14 (int16) -> Q16.16: raw * 4, exact (|raw| * 4 <= 131072), never saturates.
//   force: mN (int16) -> N: Q16_16::from_ratio(mN, 1000), same rounding; |mN| <= 32768 gives
//     |N| <= 32.768, never saturates.
//   quaternion norm check: w² + x² + y² + z² of the Q2.14 integers, exact in int64 at 2^-28
//     (each square <= 2^30, the sum <= 2^32), compared with 1 ± tolerance (tolerance Q16.16 << 12).
//
// Storage: fixed (a 256-byte framer ring, a kSampleQueueCapacity-sample queue, per-source state,
// a kReadChunkBytes buffer on the stack of service());
// no heap, no exceptions; every loop is bounded by a compile-time constant or by the length of
// the caller's span (receive()).  Firmware rules (cmake/firmware_flags.cmake).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "fixed_point/q_format.hpp"
#include "hal/clock.hpp"
#include "hal/serial_port.hpp"
#include "messages/em_tracker_samples.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace scopekin::drivers {

using fixed_point::Q16_16;
using hal::MonotonicClock;
using hal::SerialPort;
using hal::SerialStatus;
using namespace messages;  // the samples and fault flags this driver publishes

struct EmTrackerDriverConfig {
    /// A monitored source with no valid sample for longer than this is stale.  Default: 100 ms,
    /// three periods of the bench's 30 Hz streams (model/PHYSICS.md §6), so one late or corrupted frame
    /// never flags a sensor but a sensor that stopped is flagged within 0.1 s.
    std::uint32_t stale_timeout_us{100'000};
    /// Largest accepted |x|, |y|, |z| of a position, µm (default 1 m).
    std::int32_t max_position_um{1'000'000};
    /// Largest accepted |component| of the tip force, mN (default 25 N).
    std::int32_t max_force_mN{25'000};
    /// Accepted |w² + x² + y² + z² - 1| of the orientation (default 0.02, raw 1311).
    Q16_16 quaternion_norm_squared_tolerance{Q16_16::from_ratio(2, 100)};
    /// EmTrackerSource bits whose staleness is tracked (sensors the bench has plugged in).
    std::uint8_t monitored_sources{kEmAllSources};
};

/// Counters since construction (wrap at 2^32).  A sample with several faults counts in each.
struct EmTrackerDriverCounters {
    std::uint32_t poses_ok{0};       ///< valid poses (no fault flag)
    std::uint32_t tip_forces_ok{0};  ///< valid tip forces
    std::uint32_t unknown_sensor{0};
    std::uint32_t out_of_range{0};
    std::uint32_t quaternion_norm{0};
    std::uint32_t timestamp_backwards{0};  ///< device time not increasing (backwards or repeated)
    std::uint32_t device_status{0};
    std::uint32_t stale_events{0};     ///< fresh -> stale transitions of monitored sources
    std::uint32_t samples_dropped{0};  ///< queue overflows (oldest sample dropped)
    std::uint32_t malformed_payload{
        0};  ///< frames the decoder refused (cannot happen: the framer checks)
    std::uint32_t serial_closed{0};            ///< reads that returned SerialStatus::closed
    std::uint32_t serial_errors{0};            ///< reads that returned SerialStatus::failed
    protocol::EmTrackerFramerCounters link{};  ///< bad checksum, bad length, unknown type, ...
};

/// What one service() call did.
struct EmTrackerServiceResult {
    SerialStatus status{SerialStatus::timeout};  ///< ok if any byte was read, else the last status
    std::uint32_t bytes_read{0};
    std::uint32_t samples{0};  ///< samples queued (valid or flagged)
};

class EmTrackerDriver {
public:
    /// Bytes per SerialPort::read() call and reads per service(): service() reads until the port
    /// has no more (a short read) or kMaxBytesPerService = 1024 bytes are in.  Sized from the
    /// fastest line the bench uses: 921,600 bit/s 8N1 carries 92,160 bytes/s, 460.8 bytes per
    /// 5 ms period, so one service reads a saturated line completely at any period up to 11.1 ms
    /// (2.2 times a 5 ms period's bytes: a late period is caught up by the next), and a 115,200
    /// bit/s line (11,520 bytes/s) at any period up to 88 ms.  A chunk plus a partial frame fits
    /// the framer's ring (128 + 31 <= 256), so receive() never overflows it.
    static constexpr std::size_t kReadChunkBytes = 128;
    static constexpr std::size_t kReadsPerService = 8;
    static constexpr std::size_t kMaxBytesPerService = kReadChunkBytes * kReadsPerService;
    /// Samples held until pop(); one service() completes at most 62 frames (1024 new bytes plus a
    /// partial frame of at most 31 from the previous call, 17-byte smallest frame), so a consumer
    /// that drains the queue after every service() never loses one.
    static constexpr std::size_t kSampleQueueCapacity = 64;
    static_assert(kReadChunkBytes + protocol::kEmTrackerMaxFrameSize - 1U <=
                  protocol::kEmTrackerFramerCapacity);
    static_assert((kMaxBytesPerService + protocol::kEmTrackerMaxFrameSize - 1U) /
                      protocol::kEmTrackerMinFrameSize <=
                  kSampleQueueCapacity);

    explicit EmTrackerDriver(const EmTrackerDriverConfig& config = {}) noexcept;

    /// Reads what the port has (timeout 0, at most kMaxBytesPerService bytes), turns the frames
    /// into queued samples stamped `now_us`, then poll(now_us).
    EmTrackerServiceResult service(SerialPort& port, std::uint64_t now_us) noexcept;
    /// The same, stamped with clock.now_us() (read once, before the first read).
    EmTrackerServiceResult service(SerialPort& port, const MonotonicClock& clock) noexcept;
    /// The same for bytes from elsewhere (a recording, a test): work proportional to bytes.size().
    /// Returns the number of samples queued.
    std::size_t receive(std::span<const std::uint8_t> bytes, std::uint64_t now_us) noexcept;
    /// Staleness: marks every monitored source stale whose last valid sample is older than the
    /// timeout at `now_us` (a source that never sent is stale from the start).
    void poll(std::uint64_t now_us) noexcept;

    /// Oldest queued sample; false if the queue is empty.
    [[nodiscard]] bool pop(EmTrackerSample& sample) noexcept;
    [[nodiscard]] std::size_t queued() const noexcept { return queue_size_; }

    [[nodiscard]] bool stale(EmSensor sensor) const noexcept;
    [[nodiscard]] bool tip_force_stale() const noexcept;
    /// EmTrackerSource bits of the sources stale now.
    [[nodiscard]] std::uint8_t stale_sources() const noexcept { return stale_mask_; }
    /// Latest VALID sample of a sensor (all zero before the first one; see has_pose()).
    [[nodiscard]] const EmPoseSample& latest_pose(EmSensor sensor) const noexcept;
    [[nodiscard]] bool has_pose(EmSensor sensor) const noexcept;
    [[nodiscard]] const TipForceSample& latest_tip_force() const noexcept { return latest_force_; }
    [[nodiscard]] bool has_tip_force() const noexcept {
        return (valid_mask_ & kEmSourceTipForce) != 0U;
    }

    /// kEmFaultStale if a monitored source is stale now, plus every fault event since the last
    /// take_fault_flags().
    [[nodiscard]] std::uint32_t fault_flags() const noexcept;
    /// fault_flags(), then forgets the events (the cyclic executive calls it once per period).
    std::uint32_t take_fault_flags() noexcept;

    [[nodiscard]] EmTrackerDriverCounters counters() const noexcept;
    /// Bytes of a frame still arriving (held by the framer, < kEmTrackerMaxFrameSize).
    [[nodiscard]] std::size_t buffered_bytes() const noexcept { return framer_.buffered(); }
    [[nodiscard]] const EmTrackerDriverConfig& config() const noexcept { return config_; }

private:
    /// False (counted as malformed_payload) if the decoder refused the frame.
    [[nodiscard]] bool handle_frame(const protocol::EmTrackerFrame& frame,
                                    std::uint64_t now_us) noexcept;
    void handle_pose(const protocol::EmPoseMessage& message, std::uint64_t now_us) noexcept;
    void handle_tip_force(const protocol::TipForceMessage& message, std::uint64_t now_us) noexcept;
    /// Checks device time against the source's previous one and makes it the new reference.
    [[nodiscard]] bool device_time_increases(std::size_t source,
                                             std::uint32_t device_time_us) noexcept;
    void count_sample_faults(std::uint32_t flags) noexcept;
    void mark_valid(std::size_t source, std::uint64_t now_us) noexcept;
    void enqueue(const EmTrackerSample& sample) noexcept;
    void note_link_faults(const protocol::EmTrackerFramerCounters& before) noexcept;

    EmTrackerDriverConfig config_;
    protocol::EmTrackerFramer framer_{};

    std::array<EmTrackerSample, kSampleQueueCapacity> queue_{};
    std::size_t queue_head_{0};
    std::size_t queue_size_{0};

    std::array<EmPoseSample, kEmSensorCount> latest_pose_{};
    TipForceSample latest_force_{};
    std::array<std::uint64_t, kEmSourceCount>
        last_valid_us_{};  ///< receive time of the last valid sample
    std::array<std::uint32_t, kEmSourceCount>
        last_device_time_us_{};         ///< reference for the time check
    std::uint8_t valid_mask_{0};        ///< sources that have had a valid sample
    std::uint8_t device_time_mask_{0};  ///< sources with a device time reference
    std::uint8_t stale_mask_{0};
    std::uint32_t event_flags_{0};
    EmTrackerDriverCounters counters_{};
};

}  // namespace scopekin::drivers
