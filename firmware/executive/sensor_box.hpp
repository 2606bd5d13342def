// sensor_box.hpp — the box's cyclic executive: once per period, read → step → monitor → publish.
//
//   read     drain the CAN receive queue (at most kMaxFramesPerPeriod frames per period; the rest
//            wait in the backend's queue for the next period), hand each frame to its driver,
//            track the controller's health from error frames; service the serial sensors
//            (EM tracker, tip force: validated, counted and flagged; the latest valid sample of
//            each source is kept for the estimator's input, kinetics::TrackerInputs)
//   step     kinetics::step on the Inputs assembled from the drivers' messages
//            (estimator_inputs.hpp; the estimator validates them again and holds stale signals)
//   monitor  the estimator's monitors (self-lock, contact force) run inside step
//   publish  KineticEstimate, ContactSummary, Alarms, EstimateEvidence, one StationForces and one
//            BoxCounters frame every period; BoxStatus every `status_every_periods` and at once in any period whose
//            fault bits differ from the last BoxStatus sent
//
// It uses only the HAL interfaces (hal::CanBus, hal::SerialPort); `main` picks the backends and
// the clock and calls run_period() at each release.  No heap, no exceptions; all state is in the
// object, which `main` keeps in static storage.
//
// Receive filter: init() asks the CAN backend to pass only the handle sensors' identifiers
// (drivers::kHandleSensorReceiveFilters) and error frames; SocketCAN does it in the kernel, the
// loopback wire and `scopekin replay` in software, so a flood of foreign frames never reaches the
// queue the box reads.  On a backend that cannot filter (receive_filtered() false) every frame
// is read and the foreign ones are counted (unknown_ids, kBoxFaultUnknownId).
//
// Backlog: frames that wait in the receive queue for longer than a period are flagged
// (kBoxFaultReceiveBacklog) in every period that (1) read its cap of kMaxFramesPerPeriod frames
// (more may be waiting), or (2) read a frame received before the previous period ran and more
// than a period before this one (it waited through a period: a backlog being drained), or
// (3) found the newest handle sample older than a period (the driver holds it, not fresh: the
// estimator never takes history for a live reading).  Each such period counts in
// BoxCounters::backlog_periods (BoxCounters index receive_backlog on the wire), each frame of (2)
// in late_frames.  A box that stalled (say 100 ms: 210 frames waiting) thus reads its cap, holds
// its inputs and flags the backlog, reads the rest in the next period (still flagged: they
// waited through a period) and clears the bit in the first period that finds only frames that
// arrived since the one before.  A shorter stall whose frames fit the cap is a period overrun
// (main's timer), not a backlog: its newest samples are fresh.
//
// Faults: a sensor that stops sending is flagged stale in the first period its last sample is
// older than HandleSensorConfig::stale_after_us (default 3 periods); the kinetics holds its
// last value and sets its own stale flag in every period without a fresh sample, so the next
// BoxStatus (sent at once because the bits changed) reports it, and KineticEstimate.InputsStale
// marks the held estimate.  When samples return, the flags clear the same way.
// The fault bits of a period (messages/box_faults.hpp, the box's one fault vocabulary) are taken
// after `step`, before `publish`: a send that fails is reported (kBoxFaultSendFailed) from the
// next period on.
#pragma once

#include <cstdint>

#include "drivers/em_tracker_driver.hpp"
#include "drivers/handle_sensors.hpp"
#include "executive/can_health.hpp"
#include "hal/can_bus.hpp"
#include "hal/serial_port.hpp"
#include "kinetics/kinetics.hpp"
#include "messages/box_faults.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace scopekin::executive {

/// Frames read per period at most (bounded work).  At 1 kHz per sensor and 5 ms periods the box
/// sees 10 input frames per period; 128 leaves room for 64 ms periods or bursts.
inline constexpr std::uint16_t kMaxFramesPerPeriod = 128;

struct BoxConfig {
    std::uint32_t period_us{5000};  ///< 1 ms .. 1 s; sets kinetics.period_s
    kinetics::Config kinetics{};    ///< period_s is overwritten from period_us
    drivers::HandleSensorConfig handle_sensors{};
    drivers::EmTrackerDriverConfig em_tracker{};
    std::uint16_t status_every_periods{20};  ///< heartbeat: 100 ms at 5 ms
    std::uint32_t send_timeout_us{0};        ///< per frame; 0: never block the period
};

struct BoxCounters {
    std::uint32_t periods{0};
    std::uint32_t frames_read{0};  ///< everything received (data and error frames)
    std::uint32_t unknown_ids{0};  ///< data frames no driver claimed
    std::uint32_t frames_published{0};
    std::uint32_t send_failures{0};
    std::uint32_t period_overruns{0};  ///< as reported by main's timer
    std::uint32_t backlog_periods{0};  ///< periods with kBoxFaultReceiveBacklog
    std::uint32_t late_frames{0};      ///< frames that waited in the queue through a period
};

class SensorBox {
public:
    /// Validates the configuration and initialises the estimator.  `serial` may be null (no
    /// test-bench sensors).  Returns false if the estimator refused its configuration: the box
    /// still runs and publishes, with BoxState no_estimate and EstimateValid 0.
    bool init(const BoxConfig& config, hal::CanBus& can, hal::SerialPort* serial);

    /// One period released at `now_us` (the clock of the CAN backend's timestamps).
    /// `period_overruns` is main's running count of skipped periods.
    void run_period(std::uint64_t now_us, std::uint32_t period_overruns);

    [[nodiscard]] const kinetics::Outputs& outputs() const { return outputs_; }
    [[nodiscard]] const BoxCounters& counters() const { return counters_; }
    [[nodiscard]] const drivers::HandleSensors& handle_sensors() const { return handle_sensors_; }
    [[nodiscard]] const drivers::EmTrackerDriver& em_tracker() const { return em_tracker_; }
    /// The tracker part of the estimator's last Inputs (all zero without a serial port).
    [[nodiscard]] const kinetics::TrackerInputs& tracker_inputs() const { return tracker_; }
    /// BoxStatus.TrackerFaults of the last period (0 without a serial port).
    [[nodiscard]] std::uint8_t tracker_faults() const { return tracker_faults_; }
    [[nodiscard]] const CanHealth& can_health() const { return can_health_; }
    [[nodiscard]] const hal::CanCounters can_counters() const { return can_->counters(); }
    /// Fault bits of the last period (messages::BoxFault; BoxStatus.DriverFaults on the wire).
    [[nodiscard]] std::uint16_t box_faults() const { return box_faults_; }
    [[nodiscard]] protocol::BoxState box_state() const { return box_state_; }
    /// True if the CAN backend took the receive filter at init (false: it passes every frame).
    [[nodiscard]] bool receive_filtered() const { return receive_filtered_; }

private:
    void read_can(std::uint64_t now_us);
    void read_serial(std::uint64_t now_us);
    void publish(const hal::CanFrame& frame);
    void publish_outputs();
    void publish_status(bool faults_changed);
    [[nodiscard]] std::uint32_t counter_value(protocol::BoxCounterIndex index) const;

    BoxConfig config_{};
    hal::CanBus* can_{nullptr};
    hal::SerialPort* serial_{nullptr};
    bool estimator_ok_{false};
    bool receive_filtered_{false};
    bool has_last_period_{false};
    std::uint64_t last_period_us_{0};  ///< now_us of the previous period
    kinetics::State kinetics_{};
    kinetics::Outputs outputs_{};
    drivers::HandleSensors handle_sensors_{};
    drivers::EmTrackerDriver em_tracker_{};
    kinetics::TrackerInputs tracker_{};
    std::uint8_t tracker_faults_{0};
    CanHealth can_health_{};
    BoxCounters counters_{};
    protocol::BoxState box_state_{protocol::BoxState::starting};
    std::uint16_t box_faults_{0};
    std::uint16_t period_faults_{0};  ///< gathered during the period
    std::uint32_t last_can_dropped_{0};
    std::uint16_t last_status_box_faults_{0};
    std::uint16_t last_status_kinetic_faults_{0};
    std::uint8_t last_status_tracker_faults_{0};
    std::uint16_t periods_since_status_{0};
    std::uint8_t heartbeat_{0};
    std::uint8_t station_cursor_{0};
    std::uint8_t counter_cursor_{0};
    std::uint8_t self_lock_raised_{0};
    std::uint8_t critical_raised_{0};
    bool last_self_lock_{false};
    bool last_critical_{false};
};

}  // namespace scopekin::executive
