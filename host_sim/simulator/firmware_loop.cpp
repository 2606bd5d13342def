#include "host_sim/simulator/firmware_loop.hpp"

#include "kinetics/default_reduced_tables.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace scopekin::host_sim {

FirmwareLoop::FirmwareLoop(PeriodCallback on_period, std::uint32_t period_us)
    : on_period_(std::move(on_period)),
      period_us_(period_us),
      next_period_us_(period_us),
      clock_(std::make_unique<hal::SimulatedClock>(0)),
      wire_(std::make_unique<hal::LoopbackCanWire>(*clock_)),
      serial_(std::make_unique<hal::LoopbackSerialPort>()),
      box_(std::make_unique<executive::SensorBox>()) {
    executive::BoxConfig config{};
    config.period_us = period_us_;
    config.kinetics = kinetics::default_config();  // the default tables and trees
    estimator_ok_ = box_->init(config, wire_->box(), serial_.get());
    feeder_ = std::make_unique<recording::DeviceFeeder>(wire_->world(), *serial_, clock_.get());
}

FirmwareLoop::~FirmwareLoop() = default;

void FirmwareLoop::deliver(const recording::RecordingRow& row) {
    const auto time_us = static_cast<std::uint64_t>(row.time_us);
    if (!started_) {
        started_ = true;
        // Switched on with the first row: the first period is the first release at or after it.
        if (next_period_us_ < time_us)
            next_period_us_ = (time_us + period_us_ - 1) / period_us_ * period_us_;
    }
    while (next_period_us_ < time_us)
        run_period(next_period_us_);
    feeder_->feed(row);  // advances the clock to the row's time
}

void FirmwareLoop::finish(std::uint64_t end_us) {
    while (next_period_us_ <= end_us)
        run_period(next_period_us_);
}

void FirmwareLoop::run_period(std::uint64_t time_us) {
    if (time_us > clock_->now_us()) clock_->advance_to(time_us);
    box_->run_period(time_us, 0);
    next_period_us_ = time_us + period_us_;
    ++periods_;
    // Drain what the box published, as a CAN observer would (the wire's queue is bounded).
    hal::ReceivedCanFrame received{};
    while (wire_->world().receive(received, 0) == hal::CanStatus::ok) {
        switch (received.frame.id) {
            case protocol::kKineticEstimateId: ++published_.estimates; break;
            case protocol::kContactSummaryId: ++published_.summaries; break;
            case protocol::kAlarmsId: ++published_.alarms; break;
            case protocol::kStationForcesId: ++published_.stations; break;
            case protocol::kBoxCountersId: ++published_.counters; break;
            case protocol::kEstimateEvidenceId: ++published_.evidence; break;
            case protocol::kBoxStatusId: ++published_.status; break;
            default: ++published_.other; break;
        }
    }
    if (on_period_) on_period_({time_us, &box_->outputs(), box_->box_faults(), box_.get()});
}

}  // namespace scopekin::host_sim
