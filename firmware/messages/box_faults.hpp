// box_faults.hpp — the box's one fault vocabulary: the bits it publishes in BoxStatus
// (scopekin.dbc: DriverFaults, TrackerFaults) and KineticEstimate (InputsStale, DepthClamped),
// and every translation into them from the flags of the EM tracker driver and the estimator.
//
// The handle-sensor driver and the executive set BoxFault bits directly.  The EM tracker driver
// flags each sample (messages::EmTrackerFault, finer than the wire's 8 bits) and the estimator
// has its own kinetics::FaultFlag (published whole as KineticFaults); the functions below are
// the only places those are mapped onto the wire's bits.  A bit is set for every period in which
// the problem was seen (stale and bus-off: for as long as they last).
#pragma once

#include <cstdint>

#include "kinetics/kinetics_io.hpp"
#include "messages/em_tracker_samples.hpp"

namespace scopekin::messages {

/// BoxStatus.DriverFaults: faults of the box's inputs, its CAN controller and its schedule.
enum BoxFault : std::uint16_t {
    kBoxFaultForceTorqueStale = 1U << 0U,  ///< handle driver: no valid force/torque sample lately
    kBoxFaultEncoderStale = 1U << 1U,      ///< handle driver: no valid insertion/roll sample lately
    kBoxFaultBadLength = 1U << 2U,         ///< handle driver: a frame's DLC differs from the DBC
    kBoxFaultUnknownId = 1U << 3U,         ///< executive: a data frame no driver claimed
    kBoxFaultOutOfRange = 1U << 4U,        ///< handle driver: a value the box cannot represent
    kBoxFaultSensorStatus = 1U << 5U,      ///< handle driver: the sensor flagged its sample
    kBoxFaultCounterGap = 1U << 6U,        ///< handle driver: the rolling counter skipped
    kBoxFaultCanErrorFrame = 1U << 7U,     ///< executive: the controller reported an error frame
    kBoxFaultBusOff = 1U << 8U,            ///< executive: the controller is bus-off
    kBoxFaultReceiveDropped = 1U << 9U,    ///< executive: the CAN backend dropped received frames
    kBoxFaultSendFailed = 1U << 10U,       ///< executive: a frame could not be sent
    kBoxFaultSerialFraming = 1U << 11U,  ///< EM tracker: checksum, length, type, no sync, overflow
    kBoxFaultTrackerStale = 1U << 12U,   ///< EM tracker: a monitored source went quiet
    kBoxFaultPeriodOverrun = 1U << 13U,  ///< executive: main's timer skipped a period
    /// executive / handle driver: received frames wait longer than a period: the period read its
    /// cap (executive::kMaxFramesPerPeriod), read a frame that was queued before the previous
    /// period ran, or the newest handle sample it read was older than a period (not fresh)
    kBoxFaultReceiveBacklog = 1U << 14U,
};
/// Every BoxFault bit (a new fault moves this to its own bit; checks reject any bit beyond).
inline constexpr std::uint16_t kAllBoxFaults = (kBoxFaultReceiveBacklog << 1U) - 1U;

/// BoxStatus.TrackerFaults: the EM tracker / tip force sensor (0 without a serial port).
enum TrackerFault : std::uint8_t {
    kTrackerFaultStale = 1U << 0U,
    kTrackerFaultOutOfRange = 1U << 1U,
    kTrackerFaultQuaternionNorm = 1U << 2U,
    kTrackerFaultDeviceTime = 1U << 3U,
    kTrackerFaultUnknownSensor = 1U << 4U,
    kTrackerFaultDeviceStatus = 1U << 5U,
    kTrackerFaultFraming = 1U << 6U,  ///< checksum, length, type, no sync or ring overflow
    kTrackerFaultLink = 1U << 7U,     ///< serial port closed or failed, or sample queue overflow
};

/// The EM tracker driver's flags as the wire's TrackerFaults bits.
[[nodiscard]] constexpr std::uint8_t tracker_faults_of(std::uint32_t em_flags) noexcept {
    // The six sample-level flags are bits 0..5 of both vocabularies.
    constexpr std::uint32_t kSame = kEmFaultStale | kEmFaultOutOfRange | kEmFaultQuaternionNorm |
                                    kEmFaultTimestamp | kEmFaultUnknownSensor |
                                    kEmFaultDeviceStatus;
    static_assert(kSame == (kTrackerFaultStale | kTrackerFaultOutOfRange |
                            kTrackerFaultQuaternionNorm | kTrackerFaultDeviceTime |
                            kTrackerFaultUnknownSensor | kTrackerFaultDeviceStatus));
    constexpr std::uint32_t kFraming = kEmFaultBadChecksum | kEmFaultBadLength |
                                       kEmFaultUnknownType | kEmFaultBufferOverflow |
                                       kEmFaultNoSync;
    constexpr std::uint32_t kLink = kEmFaultSerial | kEmFaultQueueOverflow;
    std::uint32_t faults = em_flags & kSame;
    if ((em_flags & kFraming) != 0U) faults |= kTrackerFaultFraming;
    if ((em_flags & kLink) != 0U) faults |= kTrackerFaultLink;
    return static_cast<std::uint8_t>(faults);
}

/// The EM tracker driver's flags as DriverFaults bits (framing and staleness).
[[nodiscard]] constexpr std::uint16_t box_faults_of_tracker(std::uint32_t em_flags) noexcept {
    const std::uint8_t tracker = tracker_faults_of(em_flags);
    std::uint16_t faults = 0;
    if ((tracker & kTrackerFaultFraming) != 0U) faults |= kBoxFaultSerialFraming;
    if ((tracker & kTrackerFaultStale) != 0U) faults |= kBoxFaultTrackerStale;
    return faults;
}

/// KineticEstimate.InputsStale: a handle signal is stale, its last value is held.
[[nodiscard]] constexpr bool inputs_stale(std::uint32_t kinetic_faults) noexcept {
    constexpr std::uint32_t kStale = kinetics::kFaultInsertionStale | kinetics::kFaultForceStale |
                                     kinetics::kFaultTorqueStale | kinetics::kFaultRollStale;
    return (kinetic_faults & kStale) != 0U;
}

/// KineticEstimate.DepthClamped: the depth the model uses is not the reading.
[[nodiscard]] constexpr bool depth_clamped(std::uint32_t kinetic_faults) noexcept {
    constexpr std::uint32_t kDepth = kinetics::kFaultInsertionRange |
                                     kinetics::kFaultInsertionJump |
                                     kinetics::kFaultDepthOutsideModel;
    return (kinetic_faults & kDepth) != 0U;
}

}  // namespace scopekin::messages
