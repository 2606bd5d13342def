// handle_sensors.hpp — driver of the handle's CAN sensors (force/torque cell 0x110, insertion/
// roll encoder 0x111): decodes frames, validates them and keeps the latest valid sample of each,
// time-stamped with the frame's receive time; publishes them once per period as
// messages::HandleSamples (the executive turns those into the estimator's Inputs).
//
// Validation of each frame (each fault counted, and flagged for the period it happened in):
//   bad length     DLC differs from scopekin.dbc
//   out of range   a value the receiver cannot represent (insertion beyond ±32 m)
//   sensor status  the sensor itself says the sample is not valid (status bits)
//   counter gap    the 4-bit rolling counter skipped: frames were lost upstream (the sample
//                  is still used — it is valid, only older ones are missing)
// A rejected frame never changes the held sample.  Frames of other identifiers are not this
// driver's (accept() returns false) — the executive counts unknown identifiers.  The identifiers
// it accepts are kHandleSensorReceiveFilters: the executive sets them as the CAN backend's
// receive filter, so on a backend that filters (SocketCAN, loopback) no other frame reaches it.
//
// Freshness by time: the estimator sees a signal as fresh in a period only if a new valid sample
// arrived since the last period AND that sample's receive time is at most `max_sample_age_us`
// (one period: SensorBox::init sets it) before the period's `now_us`.  A newer sample read late —
// from a backlog in the receive queue, after a stall — is history, not a live reading: it is held
// (not fresh), counted (late_samples) and flagged (kBoxFaultReceiveBacklog), so a backlog can
// never walk the estimator through old samples as if they were live.
//
// Staleness: a sensor whose last valid sample is older than `stale_after_us` is stale (its
// BoxFault bit is set each period until a valid sample arrives; each onset counts one stale
// event).  The estimator holds its last value of a signal in every period it is not fresh
// (kinetics.hpp "Bad input").
#pragma once

#include <array>
#include <cstdint>

#include "hal/can_bus.hpp"
#include "messages/box_faults.hpp"
#include "messages/handle_samples.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace scopekin::drivers {

struct HandleSensorConfig {
    std::uint32_t stale_after_us{15000};  ///< 3 periods of 5 ms; the sensors send at 1 kHz
    /// A sample older than this at take_samples() is not fresh (late).  One period; set from
    /// BoxConfig::period_us by SensorBox::init.  At 1 kHz the newest sample of a period is at
    /// most ~1 ms old, so only a backlog (or a clock step) makes it late.
    std::uint32_t max_sample_age_us{5000};
};

/// The frames this driver accepts, as CAN receive filters (standard data frames 0x110, 0x111).
inline constexpr std::array<hal::CanIdFilter, 2> kHandleSensorReceiveFilters{{
    {protocol::kHandleForceTorqueId, hal::kCanStandardIdMask, false},
    {protocol::kInsertionRollId, hal::kCanStandardIdMask, false},
}};

struct HandleSensorCounters {
    std::uint32_t force_torque_samples{0};  ///< valid samples taken
    std::uint32_t insertion_roll_samples{0};
    std::uint32_t bad_length{0};
    std::uint32_t out_of_range{0};
    std::uint32_t sensor_status{0};
    std::uint32_t counter_gaps{0};  ///< frames missing according to the counters
    std::uint32_t stale_events{0};  ///< times a sensor went stale
    /// Periods in which a sensor's newest sample was older than max_sample_age_us: held, not
    /// fresh (one per sensor and period)
    std::uint32_t late_samples{0};
};

class HandleSensors {
public:
    explicit HandleSensors(const HandleSensorConfig& config = {}) : config_(config) {}

    /// Offers one received frame.  Returns true if it was a handle-sensor frame (whether valid
    /// or not), false if it belongs to someone else.
    bool accept(const hal::ReceivedCanFrame& received);

    /// The samples of the period released at `now_us`: the held samples, fresh for sensors that
    /// delivered a valid sample since the last call, received at most max_sample_age_us before
    /// `now_us`.  Updates staleness.
    [[nodiscard]] messages::HandleSamples take_samples(std::uint64_t now_us);

    /// messages::BoxFault bits of the period closed by the last take_samples().
    [[nodiscard]] std::uint16_t faults() const { return faults_; }
    [[nodiscard]] const HandleSensorCounters& counters() const { return counters_; }

private:
    struct Channel {
        bool seen{false};   ///< a valid sample arrived at least once
        bool fresh{false};  ///< ... since the last take_samples()
        bool stale{true};
        bool counter_known{false};
        std::uint8_t last_counter{0};
        std::uint64_t last_sample_us{0};
    };
    void note_counter(Channel& channel, std::uint8_t counter);
    void update_staleness(Channel& channel, std::uint64_t now_us, std::uint16_t stale_bit);
    /// channel.fresh, unless its sample is older than max_sample_age_us (late: counted, flagged).
    [[nodiscard]] bool take_fresh(Channel& channel, std::uint64_t now_us);

    HandleSensorConfig config_;
    HandleSensorCounters counters_{};
    Channel force_torque_{};
    Channel insertion_roll_{};
    messages::ForceTorqueSample force_torque_sample_{};
    messages::InsertionRollSample insertion_roll_sample_{};
    std::uint16_t pending_faults_{0};  ///< gathered by accept() during the period
    std::uint16_t faults_{0};
};

}  // namespace scopekin::drivers
