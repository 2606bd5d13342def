#pragma once
// The unmodified firmware on the host: the box's cyclic executive (firmware/executive/SensorBox)
// on the loopback HAL (a CAN wire, a serial line, a simulated clock), fed one recording row at a
// time. Live simulations and recorded data go through this one class, so a recording written by
// `scopekin simulate` and read back by `scopekin run` gives bit-identical firmware outputs.
//
// Time. Rows carry their arrival time (us). The box's periods are released at k * period_us
// (k = 1, 2, ...), from the first row on: the box is switched on with the first row, so a
// recording that starts late (a logger's clock at 500 s) runs its own periods, not every empty
// one from 0. A period at T runs once every row with time <= T has been delivered: before a row
// later than T is delivered, and in finish(). The clock stands at the row's time while its
// frames are sent, so the drivers time-stamp them as a real CAN controller would. Every period
// between two rows runs (the readers bound the time between rows: --max-gap-s).
#include <cstdint>
#include <functional>
#include <memory>

#include "executive/sensor_box.hpp"
#include "hal/loopback/loopback_can.hpp"
#include "hal/loopback/loopback_serial.hpp"
#include "hal/loopback/simulated_clock.hpp"
#include "host_sim/recording/device_feeder.hpp"
#include "host_sim/recording/recording_row.hpp"

namespace scopekin::host_sim {

/// The firmware's period: the box's 200 Hz (BoxConfig default).
inline constexpr std::uint32_t kBoxPeriodUs = 5000;

/// What the box did in one period: its release time and the estimator's outputs, and the box
/// itself for its fault bits and counters (null: only box_faults is known).
struct BoxPeriod {
    std::uint64_t time_us = 0;
    const kinetics::Outputs* outputs = nullptr;
    std::uint16_t box_faults = 0;  ///< messages::BoxFault bits (BoxStatus.DriverFaults)
    const executive::SensorBox* box = nullptr;
};

/// Frames the box published, by message (drained from the wire every period).
struct PublishedFrames {
    std::uint64_t estimates = 0, summaries = 0, alarms = 0, evidence = 0, stations = 0,
                  counters = 0, status = 0, other = 0;
};

class FirmwareLoop {
public:
    using PeriodCallback = std::function<void(const BoxPeriod&)>;
    /// Initialises the box (the default reduced tables, `period_us`). `on_period` sees every period.
    explicit FirmwareLoop(PeriodCallback on_period, std::uint32_t period_us = kBoxPeriodUs);
    ~FirmwareLoop();
    FirmwareLoop(const FirmwareLoop&) = delete;
    FirmwareLoop& operator=(const FirmwareLoop&) = delete;

    /// Runs the periods due before the row's time, then sends the row's frames and bytes.
    /// Rows must come in strictly increasing time (the reader checks recordings).
    void deliver(const recording::RecordingRow& row);
    /// Runs the periods up to and including `end_us`.
    void finish(std::uint64_t end_us);

    bool estimator_ok() const { return estimator_ok_; }
    std::uint64_t periods() const { return periods_; }
    const PublishedFrames& published() const { return published_; }
    const executive::SensorBox& box() const { return *box_; }
    const recording::DeviceFeeder& feeder() const { return *feeder_; }

private:
    void run_period(std::uint64_t time_us);

    PeriodCallback on_period_;
    std::uint32_t period_us_;
    std::uint64_t next_period_us_;
    std::uint64_t periods_ = 0;
    bool started_ = false;  ///< a row has been delivered
    bool estimator_ok_ = false;
    PublishedFrames published_;
    std::unique_ptr<hal::SimulatedClock> clock_;
    std::unique_ptr<hal::LoopbackCanWire> wire_;
    std::unique_ptr<hal::LoopbackSerialPort> serial_;
    std::unique_ptr<executive::SensorBox> box_;
    std::unique_ptr<recording::DeviceFeeder> feeder_;
};

}  // namespace scopekin::host_sim
