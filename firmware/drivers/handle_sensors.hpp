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
// driver's (accept() returns false) — the executive counts unknown identifiers.
//
// Staleness: a sensor whose last valid sample is older than `stale_after_us` is stale (its
// BoxFault bit is set each period until a valid sample arrives; each onset counts one stale
// event).  The estimator sees a signal as fresh only in the period a new valid sample arrived,
// and holds its last value otherwise (kinetics.hpp "Bad input").
#pragma once

#include <cstdint>

#include "hal/can_bus.hpp"
#include "messages/box_faults.hpp"
#include "messages/handle_samples.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace scopekin::drivers {

struct HandleSensorConfig {
    std::uint32_t stale_after_us{15000};  ///< 3 periods of 5 ms; the sensors send at 1 kHz
};

struct HandleSensorCounters {
    std::uint32_t force_torque_samples{0};  ///< valid samples taken
    std::uint32_t insertion_roll_samples{0};
    std::uint32_t bad_length{0};
    std::uint32_t out_of_range{0};
    std::uint32_t sensor_status{0};
    std::uint32_t counter_gaps{0};  ///< frames missing according to the counters
    std::uint32_t stale_events{0};  ///< times a sensor went stale
};

class HandleSensors {
public:
    explicit HandleSensors(const HandleSensorConfig& config = {}) : config_(config) {}

    /// Offers one received frame.  Returns true if it was a handle-sensor frame (whether valid
    /// or not), false if it belongs to someone else.
    bool accept(const hal::ReceivedCanFrame& received);

    /// The samples of the period released at `now_us`: the held samples, fresh for sensors that
    /// delivered a valid sample since the last call.  Updates staleness.
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
