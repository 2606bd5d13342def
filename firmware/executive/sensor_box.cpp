// sensor_box.cpp — see sensor_box.hpp.
#include "executive/sensor_box.hpp"

#include "executive/estimator_inputs.hpp"

namespace scopekin::executive {

namespace {

using fixed_point::Q16_16;
using namespace messages;  // the box's fault vocabulary

constexpr std::uint32_t kMinPeriodUs = 1000;
constexpr std::uint32_t kMaxPeriodUs = 1000000;

std::uint8_t saturate_u8(std::uint32_t value) {
    return value > 255U ? std::uint8_t{255} : static_cast<std::uint8_t>(value);
}

}  // namespace

bool SensorBox::init(const BoxConfig& config, hal::CanBus& can, hal::SerialPort* serial) {
    config_ = config;
    if (config_.period_us < kMinPeriodUs) config_.period_us = kMinPeriodUs;
    if (config_.period_us > kMaxPeriodUs) config_.period_us = kMaxPeriodUs;
    if (config_.status_every_periods == 0U) config_.status_every_periods = 1;
    config_.kinetics.period_s =
        Q16_16::from_ratio(static_cast<std::int32_t>(config_.period_us), 1000000);
    config_.handle_sensors.max_sample_age_us = config_.period_us;
    can_ = &can;
    receive_filtered_ =
        can.set_receive_filter(drivers::kHandleSensorReceiveFilters) == hal::CanStatus::ok;
    has_last_period_ = false;
    last_period_us_ = 0;
    serial_ = serial;
    handle_sensors_ = drivers::HandleSensors{config_.handle_sensors};
    em_tracker_ = drivers::EmTrackerDriver{config_.em_tracker};
    tracker_ = kinetics::TrackerInputs{};
    kinetics::init(config_.kinetics, kinetics_);
    estimator_ok_ = kinetics_.config_fault == kinetics::ConfigFault::none;
    box_state_ = estimator_ok_ ? protocol::BoxState::starting : protocol::BoxState::no_estimate;
    last_can_dropped_ = can.counters().dropped;
    return estimator_ok_;
}

void SensorBox::read_can(std::uint64_t now_us) {
    std::uint16_t read = 0;
    bool backlog = false;
    for (; read < kMaxFramesPerPeriod; ++read) {  // bound: kMaxFramesPerPeriod
        hal::ReceivedCanFrame received{};
        if (can_->receive(received, 0) != hal::CanStatus::ok) {
            break;
        }
        ++counters_.frames_read;
        // Queued before the previous period ran, and more than a period ago: it waited.
        const std::uint64_t stamp = received.timestamp_us;
        if (has_last_period_ && stamp < last_period_us_ && now_us > stamp &&
            now_us - stamp > config_.period_us) {
            ++counters_.late_frames;
            backlog = true;
        }
        if (received.frame.error) {
            can_health_.on_error_frame(received.frame);
            period_faults_ |= kBoxFaultCanErrorFrame;
            continue;
        }
        if (!handle_sensors_.accept(received)) {
            ++counters_.unknown_ids;
            period_faults_ |= kBoxFaultUnknownId;
        }
    }
    if (read == kMaxFramesPerPeriod || backlog) {
        period_faults_ |= kBoxFaultReceiveBacklog;  // counted with the driver's late samples
    }
    const std::uint32_t dropped = can_->counters().dropped;
    if (dropped != last_can_dropped_) {
        period_faults_ |= kBoxFaultReceiveDropped;
        last_can_dropped_ = dropped;
    }
}

void SensorBox::read_serial(std::uint64_t now_us) {
    (void)em_tracker_.service(*serial_, now_us);
    tracker_.fresh_mask = 0;  // fresh: a valid sample arrived in this period
    EmTrackerSample sample{};
    for (std::size_t n = 0; n < drivers::EmTrackerDriver::kSampleQueueCapacity; ++n) {  // bound
        if (!em_tracker_.pop(sample)) {
            break;
        }
        keep_tracker_sample(sample, tracker_);
    }
    tracker_.stale_mask = em_tracker_.stale_sources();
    const std::uint32_t flags = em_tracker_.take_fault_flags();
    tracker_faults_ = tracker_faults_of(flags);
    period_faults_ |= box_faults_of_tracker(flags);
}

void SensorBox::publish(const hal::CanFrame& frame) {
    const hal::CanStatus status = can_->send(frame, config_.send_timeout_us);
    if (status == hal::CanStatus::ok) {
        ++counters_.frames_published;
        can_health_.on_sent();
    } else {
        ++counters_.send_failures;
        period_faults_ |= kBoxFaultSendFailed;
        can_health_.on_send_failure(status);
    }
}

void SensorBox::run_period(std::uint64_t now_us, std::uint32_t period_overruns) {
    ++counters_.periods;
    if (period_overruns != counters_.period_overruns) {
        period_faults_ |= kBoxFaultPeriodOverrun;
        counters_.period_overruns = period_overruns;
    }

    // read
    read_can(now_us);
    if (serial_ != nullptr) {
        read_serial(now_us);
    }
    const kinetics::Inputs inputs = assemble_inputs(handle_sensors_.take_samples(now_us), tracker_);
    period_faults_ |= handle_sensors_.faults();
    if ((period_faults_ & kBoxFaultReceiveBacklog) != 0U) {
        ++counters_.backlog_periods;
    }
    last_period_us_ = now_us;
    has_last_period_ = true;
    if (can_health_.state() == protocol::CanState::bus_off) {
        period_faults_ |= kBoxFaultBusOff;
    }

    // step + monitor
    kinetics::step(inputs, kinetics_, outputs_);
    box_faults_ = period_faults_;
    period_faults_ = 0;

    const bool faulty = box_faults_ != 0U || outputs_.fault_flags != 0U;
    if (estimator_ok_) {
        box_state_ = faulty ? protocol::BoxState::degraded : protocol::BoxState::running;
    }

    // publish
    publish_outputs();
    static_assert(kinetics::kAllFaultFlags <= 0xFFFFU, "KineticFaults is 16 bits on the wire");
    const auto kinetic_faults = static_cast<std::uint16_t>(outputs_.fault_flags & 0xFFFFU);
    const std::uint8_t tracker_faults = tracker_faults_;
    const bool faults_changed = kinetic_faults != last_status_kinetic_faults_ ||
                                box_faults_ != last_status_box_faults_ ||
                                tracker_faults != last_status_tracker_faults_;
    publish_status(faults_changed);
}

void SensorBox::publish_outputs() {
    const auto step_counter = static_cast<std::uint8_t>(outputs_.step_index & 0xFFU);

    protocol::KineticEstimate estimate{};
    estimate.estimate_valid = estimator_ok_;
    if (estimator_ok_) {
        estimate.tip_path_mm = outputs_.tip_path_mm;
        estimate.tip_velocity_mm_per_s = outputs_.tip_velocity_mm_per_s;
        estimate.advance_efficiency = outputs_.advance_efficiency;
        estimate.tip_uncertainty_mm = outputs_.tip_uncertainty_mm;
    }
    estimate.inputs_stale = inputs_stale(outputs_.fault_flags);
    estimate.depth_clamped = depth_clamped(outputs_.fault_flags);
    estimate.step_counter = step_counter;
    publish(protocol::encode(estimate));

    protocol::ContactSummary summary{};
    std::uint16_t sticking_mask = 0;
    for (std::size_t k = 0; k < kinetics::kStationCapacity; ++k) {  // bound: 12 stations
        if (outputs_.stations[k].state == kinetics::StationState::sticking) {
            sticking_mask = static_cast<std::uint16_t>(sticking_mask | (1U << k));
        }
    }
    if (estimator_ok_) {
        summary.max_contact_force_N = outputs_.max_contact_force_N;
        summary.max_contact_path_mm = outputs_.max_contact_path_mm;
        summary.max_contact_station = outputs_.max_contact_station;
        summary.active_stations = outputs_.active_stations;
        summary.distal_sticking = outputs_.distal_sticking;
        summary.sticking_mask = sticking_mask;
    }
    summary.step_counter = step_counter;
    publish(protocol::encode(summary));

    const bool critical = outputs_.contact_force_level == kinetics::ContactForceLevel::critical;
    if (outputs_.self_lock_alarm && !last_self_lock_) ++self_lock_raised_;
    if (critical && !last_critical_) ++critical_raised_;
    last_self_lock_ = outputs_.self_lock_alarm;
    last_critical_ = critical;
    protocol::Alarms alarms{};
    alarms.valid = estimator_ok_;
    alarms.self_lock = estimator_ok_ && outputs_.self_lock_alarm;
    alarms.contact_force_level =
        estimator_ok_ ? static_cast<std::uint8_t>(outputs_.contact_force_level) : 0U;
    alarms.tip_from_model = estimator_ok_ && outputs_.tip_from_model;
    alarms.self_lock_raised = self_lock_raised_;
    alarms.critical_raised = critical_raised_;
    alarms.step_counter = step_counter;
    publish(protocol::encode(alarms));

    protocol::EstimateEvidence evidence{};
    if (estimator_ok_) {
        evidence.max_contact_force_uncertainty_N = outputs_.max_contact_force_uncertainty_N;
        evidence.loop_score = outputs_.loop_score;
        evidence.model_log_likelihood_ratio = outputs_.model_log_likelihood_ratio;
        evidence.model_self_lock = outputs_.model_self_lock_alarm;
        evidence.tip_from_tracker = outputs_.tip_from_tracker;
    }
    evidence.step_counter = step_counter;
    publish(protocol::encode(evidence));

    if (estimator_ok_ && outputs_.active_stations > 0U) {
        if (station_cursor_ >= outputs_.active_stations ||
            station_cursor_ >= kinetics::kStationCapacity) {
            station_cursor_ = 0;
        }
        const kinetics::StationEstimate& station = outputs_.stations[station_cursor_];
        protocol::StationForces forces{};
        forces.station = station_cursor_;
        forces.state = static_cast<std::uint8_t>(station.state);
        forces.normal_force_N = station.normal_force_N;
        forces.tangential_force_N = station.tangential_force_N;
        forces.path_mm = station.path_position_mm;
        forces.arc_from_tip_mm = station.arc_from_tip_mm;
        publish(protocol::encode(forces));
        ++station_cursor_;
    }

    protocol::BoxCounter counter{};
    counter.index = static_cast<protocol::BoxCounterIndex>(counter_cursor_);
    counter.value = counter_value(counter.index);
    publish(protocol::encode(counter));
    counter_cursor_ =
        static_cast<std::uint8_t>((counter_cursor_ + 1U) % protocol::kBoxCounterCount);
}

void SensorBox::publish_status(bool faults_changed) {
    ++periods_since_status_;
    if (!faults_changed && periods_since_status_ < config_.status_every_periods) {
        return;
    }
    periods_since_status_ = 0;
    protocol::BoxStatus status{};
    status.heartbeat = heartbeat_++;
    status.state = box_state_;
    status.can_state = can_health_.take_worst_state();
    status.kinetic_faults = static_cast<std::uint16_t>(outputs_.fault_flags & 0xFFFFU);
    status.driver_faults = box_faults_;
    status.period_overruns = saturate_u8(counters_.period_overruns);
    status.tracker_faults = tracker_faults_;
    last_status_kinetic_faults_ = status.kinetic_faults;
    last_status_box_faults_ = status.driver_faults;
    last_status_tracker_faults_ = status.tracker_faults;
    publish(protocol::encode(status));
}

std::uint32_t SensorBox::counter_value(protocol::BoxCounterIndex index) const {
    const hal::CanCounters can = can_->counters();
    const drivers::HandleSensorCounters& handle = handle_sensors_.counters();
    const drivers::EmTrackerDriverCounters tracker = em_tracker_.counters();
    switch (index) {
        case protocol::BoxCounterIndex::can_received: return can.received;
        case protocol::BoxCounterIndex::can_dropped: return can.dropped;
        case protocol::BoxCounterIndex::can_error_frames: return can_health_.error_frames();
        case protocol::BoxCounterIndex::can_bus_off: return can_health_.bus_off_events();
        case protocol::BoxCounterIndex::can_send_failures: return counters_.send_failures;
        case protocol::BoxCounterIndex::bad_length: return handle.bad_length;
        case protocol::BoxCounterIndex::unknown_id: return counters_.unknown_ids;
        case protocol::BoxCounterIndex::out_of_range: return handle.out_of_range;
        case protocol::BoxCounterIndex::counter_gaps: return handle.counter_gaps;
        case protocol::BoxCounterIndex::stale_events: return handle.stale_events;
        case protocol::BoxCounterIndex::serial_frames: return tracker.link.frames_ok;
        case protocol::BoxCounterIndex::serial_bad_frames:
            return tracker.link.bad_checksum + tracker.link.bad_length + tracker.link.unknown_type;
        case protocol::BoxCounterIndex::serial_bytes_discarded: return tracker.link.bytes_discarded;
        case protocol::BoxCounterIndex::period_overruns: return counters_.period_overruns;
        case protocol::BoxCounterIndex::steps: return counters_.periods;
        case protocol::BoxCounterIndex::sensor_status: return handle.sensor_status;
        case protocol::BoxCounterIndex::receive_backlog: return counters_.backlog_periods;
    }
    return 0;
}

}  // namespace scopekin::executive
