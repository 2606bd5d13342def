// em_tracker_samples.hpp — what the EM tracker driver publishes: the test bench's tracker poses
// and tip forces as plain, validated, time-stamped samples (drivers/em_tracker_driver.hpp makes
// them from the serial protocol of firmware/protocol/em_tracker/em_tracker_serial.md).
//
// Every sample carries its own validity (fault_flags, 0 = valid).  The executive hands the
// latest valid sample of each source to the estimator (kinetics::TrackerInputs) and maps the
// flags to the box's fault vocabulary (messages/box_faults.hpp).  Q16.16 throughout (mm, N,
// unit quaternion); times in µs.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "fixed_point/q_format.hpp"

namespace scopekin::messages {

using fixed_point::Q16_16;

/// Tracker sensors, by wire id (the thesis bench's S1..S4, model/PHYSICS.md §6).
enum class EmSensor : std::uint8_t {
    tip = 0,        ///< S1, at the tip
    twenty_cm = 1,  ///< S2, 20 cm from the tip
    handle = 2,     ///< S3, on the handle force monitor (the input point)
    sigmoid = 3,    ///< S4, sutured on the sigmoid colon
};
inline constexpr std::size_t kEmSensorCount = 4;

/// Sources whose freshness is tracked: bit i = sensor i, bit 4 = the tip force sensor.
enum EmTrackerSource : std::uint8_t {
    kEmSourceTip = 1U << 0U,
    kEmSourceTwentyCm = 1U << 1U,
    kEmSourceHandle = 1U << 2U,
    kEmSourceSigmoid = 1U << 3U,
    kEmSourceTipForce = 1U << 4U,
};
inline constexpr std::size_t kEmSourceCount = kEmSensorCount + 1U;
inline constexpr std::uint8_t kEmAllSources = 0x1FU;

/// Fault flags: of a sample (EmPoseSample::fault_flags, TipForceSample::fault_flags: the sample's
/// own checks) and of the driver (EmTrackerDriver::fault_flags(): stale now, plus every event
/// since the last take_fault_flags()).  messages/box_faults.hpp maps them to BoxStatus.
enum EmTrackerFault : std::uint32_t {
    kEmFaultStale = 1U << 0U,       ///< a monitored source has no valid sample within the timeout
    kEmFaultOutOfRange = 1U << 1U,  ///< position or force component beyond its limit
    kEmFaultQuaternionNorm = 1U << 2U,  ///< orientation is not a unit quaternion (within tolerance)
    kEmFaultTimestamp = 1U << 3U,       ///< device time did not increase for this source
    kEmFaultUnknownSensor = 1U << 4U,   ///< pose of a sensor id > 3
    kEmFaultDeviceStatus = 1U << 5U,    ///< the device flagged the reading (status byte != 0)
    kEmFaultBadChecksum = 1U << 6U,     ///< framer: CRC mismatch
    kEmFaultBadLength = 1U << 7U,       ///< framer: length byte wrong for the type
    kEmFaultUnknownType = 1U << 8U,     ///< framer: unknown message type
    kEmFaultBufferOverflow = 1U << 9U,  ///< framer ring could not take the bytes
    kEmFaultSerial = 1U << 10U,         ///< serial port closed or failed
    kEmFaultQueueOverflow = 1U << 11U,  ///< sample queue full: the oldest sample was dropped
    kEmFaultNoSync = 1U << 12U,  ///< framer: bytes discarded, not part of any valid frame (noise,
                                 ///< a line with no sync, the rest of a rejected frame)
};

/// Faults that make a sample unusable (any of them set: the sample is delivered but does not
/// update the latest value or the staleness timer of its source).
inline constexpr std::uint32_t kEmSampleFaults = kEmFaultOutOfRange | kEmFaultQuaternionNorm |
                                                 kEmFaultTimestamp | kEmFaultUnknownSensor |
                                                 kEmFaultDeviceStatus;

struct EmPoseSample {
    std::uint8_t sensor_id{0};            ///< wire id; an EmSensor when < kEmSensorCount
    std::array<Q16_16, 3> position_mm{};  ///< x, y, z, tracker frame
    std::array<Q16_16, 4> orientation{};  ///< unit quaternion w, x, y, z (dimensionless)
    std::uint32_t device_time_us{0};      ///< tracker clock (wraps at 2^32 µs)
    std::uint64_t receive_time_us{0};     ///< box clock (hal::MonotonicClock) when read
    std::uint8_t device_status{0};        ///< the wire's status byte
    std::uint32_t fault_flags{0};         ///< kEmSampleFaults bits; 0 = valid
};

struct TipForceSample {
    std::array<Q16_16, 3> force_N{};  ///< x, y across the tip, z along the scope axis
    std::uint32_t device_time_us{0};
    std::uint64_t receive_time_us{0};
    std::uint8_t device_status{0};
    std::uint32_t fault_flags{0};
};

enum class EmTrackerSampleKind : std::uint8_t {
    pose,
    tip_force
};

/// One entry of the driver's sample queue: `pose` or `tip_force`, as `kind` says.
struct EmTrackerSample {
    EmTrackerSampleKind kind{EmTrackerSampleKind::pose};
    EmPoseSample pose{};
    TipForceSample tip_force{};
};

}  // namespace scopekin::messages
