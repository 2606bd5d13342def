// scopekin_messages.cpp — typed encoders/decoders of the box's CAN messages (layouts as in
// scopekin.dbc; see the header for the rules).
#include "protocol/can/scopekin_messages.hpp"

namespace scopekin::protocol {
namespace {

// Factors as exact ratios: 0.005 = 1/200, 0.1 = 1/10, 0.01 = 1/100, 0.0001 = 1/10000, 0.001 = 1/1000.
namespace handle_force_torque {
constexpr CanSignal kForce{"HandleForce", 0, 16, true, 1, 200};
constexpr CanSignal kTorque{"HandleTorque", 16, 16, true, 1, 10};
constexpr CanSignal kStatus{"CellStatus", 32, 8, false, 1, 1};
constexpr CanSignal kCounter{"CellCounter", 40, 4, false, 1, 1};
constexpr std::array kSignals{kForce, kTorque, kStatus, kCounter};
constexpr std::uint8_t kLength = 6;
}  // namespace handle_force_torque

namespace insertion_roll {
constexpr CanSignal kInsertion{"Insertion", 0, 24, true, 1, 100};
constexpr CanSignal kRoll{"Roll", 24, 24, true, 1, 10000};
constexpr CanSignal kStatus{"EncoderStatus", 48, 4, false, 1, 1};
constexpr CanSignal kCounter{"EncoderCounter", 52, 4, false, 1, 1};
constexpr std::array kSignals{kInsertion, kRoll, kStatus, kCounter};
constexpr std::uint8_t kLength = 7;
}  // namespace insertion_roll

namespace box_status {
constexpr CanSignal kHeartbeat{"HeartbeatCounter", 0, 8, false, 1, 1};
constexpr CanSignal kState{"BoxState", 8, 4, false, 1, 1};
constexpr CanSignal kCanState{"CanState", 12, 2, false, 1, 1};
constexpr CanSignal kKineticFaults{"KineticFaults", 16, 16, false, 1, 1};
constexpr CanSignal kDriverFaults{"DriverFaults", 32, 16, false, 1, 1};
constexpr CanSignal kOverruns{"PeriodOverruns", 48, 8, false, 1, 1};
constexpr CanSignal kTrackerFaults{"TrackerFaults", 56, 8, false, 1, 1};
constexpr std::array kSignals{kHeartbeat,    kState,    kCanState,     kKineticFaults,
                              kDriverFaults, kOverruns, kTrackerFaults};
constexpr std::uint8_t kLength = 8;
}  // namespace box_status

namespace kinetic_estimate {
constexpr CanSignal kTipPath{"TipPath", 0, 16, true, 1, 10};
constexpr CanSignal kTipVelocity{"TipVelocity", 16, 16, true, 1, 10};
constexpr CanSignal kEfficiency{"AdvanceEfficiency", 32, 16, true, 1, 1000};
constexpr CanSignal kValid{"EstimateValid", 48, 1, false, 1, 1};
constexpr CanSignal kStale{"InputsStale", 49, 1, false, 1, 1};
constexpr CanSignal kClamped{"DepthClamped", 50, 1, false, 1, 1};
constexpr CanSignal kTipUncertainty{"TipUncertainty", 51, 5, false, 10, 1};
constexpr CanSignal kStep{"StepCounter", 56, 8, false, 1, 1};
constexpr std::array kSignals{kTipPath, kTipVelocity, kEfficiency,     kValid,
                              kStale,   kClamped,     kTipUncertainty, kStep};
constexpr std::uint8_t kLength = 8;
}  // namespace kinetic_estimate

namespace contact_summary {
constexpr CanSignal kMaxForce{"MaxContactForce", 0, 16, false, 1, 1000};
constexpr CanSignal kMaxPath{"MaxContactPath", 16, 16, false, 1, 10};
constexpr CanSignal kMaxStation{"MaxContactStation", 32, 4, false, 1, 1};
constexpr CanSignal kActive{"ActiveStations", 36, 4, false, 1, 1};
constexpr CanSignal kDistalSticking{"DistalSticking", 40, 4, false, 1, 1};
constexpr CanSignal kStickingMask{"StickingMask", 44, 12, false, 1, 1};
constexpr CanSignal kStep{"StepCounter", 56, 8, false, 1, 1};
constexpr std::array kSignals{kMaxForce,       kMaxPath,      kMaxStation, kActive,
                              kDistalSticking, kStickingMask, kStep};
constexpr std::uint8_t kLength = 8;
}  // namespace contact_summary

namespace alarms {
constexpr CanSignal kSelfLock{"SelfLockAlarm", 0, 1, false, 1, 1};
constexpr CanSignal kLevel{"ContactForceLevel", 1, 2, false, 1, 1};
constexpr CanSignal kValid{"AlarmsValid", 3, 1, false, 1, 1};
constexpr CanSignal kTipFromModel{"TipFromModel", 4, 1, false, 1, 1};
constexpr CanSignal kSelfLockRaised{"SelfLockRaised", 8, 8, false, 1, 1};
constexpr CanSignal kCriticalRaised{"CriticalRaised", 16, 8, false, 1, 1};
constexpr CanSignal kStep{"StepCounter", 24, 8, false, 1, 1};
constexpr std::array kSignals{kSelfLock,       kLevel,          kValid, kTipFromModel,
                              kSelfLockRaised, kCriticalRaised, kStep};
constexpr std::uint8_t kLength = 4;
}  // namespace alarms

namespace box_counters {
constexpr CanSignal kIndex{"CounterIndex", 0, 8, false, 1, 1};
constexpr CanSignal kValue{"CounterValue", 32, 32, false, 1, 1};
constexpr std::array kSignals{kIndex, kValue};
constexpr std::uint8_t kLength = 8;
}  // namespace box_counters

namespace estimate_evidence {
constexpr CanSignal kForceUncertainty{"MaxContactForceUncertainty", 0, 16, false, 1, 1000};
constexpr CanSignal kLoopScore{"LoopScore", 16, 16, false, 1, 10000};
constexpr CanSignal kLogRatio{"ModelLogLikelihoodRatio", 32, 16, true, 1, 100};
constexpr CanSignal kModelSelfLock{"ModelSelfLockAlarm", 48, 1, false, 1, 1};
constexpr CanSignal kTipFromTracker{"TipFromTracker", 49, 1, false, 1, 1};
constexpr CanSignal kStep{"StepCounter", 56, 8, false, 1, 1};
constexpr std::array kSignals{kForceUncertainty, kLoopScore,      kLogRatio,
                              kModelSelfLock,    kTipFromTracker, kStep};
constexpr std::uint8_t kLength = 8;
}  // namespace estimate_evidence

namespace station_forces {
constexpr CanSignal kStation{"StationIndex", 0, 4, false, 1, 1};
constexpr CanSignal kState{"StationState", 4, 2, false, 1, 1};
constexpr CanSignal kNormal{"StationNormalForce", 8, 16, false, 1, 1000};
constexpr CanSignal kTangential{"StationTangentialForce", 24, 16, false, 1, 1000};
constexpr CanSignal kPath{"StationPath", 40, 16, false, 1, 10};
constexpr CanSignal kArc{"StationArc", 56, 8, false, 5, 1};
constexpr std::array kSignals{kStation, kState, kNormal, kTangential, kPath, kArc};
constexpr std::uint8_t kLength = 8;
}  // namespace station_forces

constexpr std::array kLayouts{
    MessageLayout{"HandleForceTorque", kHandleForceTorqueId, handle_force_torque::kLength,
                  handle_force_torque::kSignals},
    MessageLayout{"InsertionRoll", kInsertionRollId, insertion_roll::kLength,
                  insertion_roll::kSignals},
    MessageLayout{"BoxStatus", kBoxStatusId, box_status::kLength, box_status::kSignals},
    MessageLayout{"KineticEstimate", kKineticEstimateId, kinetic_estimate::kLength,
                  kinetic_estimate::kSignals},
    MessageLayout{"ContactSummary", kContactSummaryId, contact_summary::kLength,
                  contact_summary::kSignals},
    MessageLayout{"Alarms", kAlarmsId, alarms::kLength, alarms::kSignals},
    MessageLayout{"BoxCounters", kBoxCountersId, box_counters::kLength, box_counters::kSignals},
    MessageLayout{"EstimateEvidence", kEstimateEvidenceId, estimate_evidence::kLength,
                  estimate_evidence::kSignals},
    MessageLayout{"StationForces", kStationForcesId, station_forces::kLength,
                  station_forces::kSignals},
};

hal::CanFrame start_frame(std::uint32_t id, std::uint8_t length) {
    hal::CanFrame frame{};
    frame.id = id;
    frame.length = length;
    return frame;
}

void put_q16(hal::CanFrame& frame, const CanSignal& signal, Q16_16 value) {
    bool saturated = false;  // encoding saturates by design (header)
    write_raw(frame.data, signal, q16_to_raw(value, signal, saturated));
}

void put_integer(hal::CanFrame& frame, const CanSignal& signal, std::int64_t value) {
    write_raw(frame.data, signal, value);  // clamped to the signal's range
}

DecodeResult check_frame(const hal::CanFrame& frame, std::uint32_t id, std::uint8_t length) {
    if (frame.error || frame.remote || frame.extended) {
        return DecodeResult::not_data;
    }
    if (frame.id != id) {
        return DecodeResult::wrong_id;
    }
    return frame.length == length ? DecodeResult::ok : DecodeResult::bad_length;
}

Q16_16 get_q16(const hal::CanFrame& frame, const CanSignal& signal, bool& saturated) {
    return raw_to_q16(read_raw(frame.data, signal), signal, saturated);
}

template <typename Unsigned>
Unsigned get_unsigned(const hal::CanFrame& frame, const CanSignal& signal) {
    return static_cast<Unsigned>(read_raw(frame.data, signal));  // unsigned signal, fits by layout
}

bool get_flag(const hal::CanFrame& frame, const CanSignal& signal) {
    return read_raw(frame.data, signal) != 0;
}

}  // namespace

std::span<const MessageLayout> message_layouts() {
    return kLayouts;
}

const MessageLayout* find_message_layout(std::uint32_t id) {
    for (const MessageLayout& layout : kLayouts) {  // bound: 9 messages
        if (layout.id == id) {
            return &layout;
        }
    }
    return nullptr;
}

// ---- HandleForceTorque ------------------------------------------------------------------------
hal::CanFrame encode(const HandleForceTorque& message) {
    using namespace handle_force_torque;
    hal::CanFrame frame = start_frame(kHandleForceTorqueId, kLength);
    put_q16(frame, kForce, message.force_N);
    put_q16(frame, kTorque, message.torque_Nmm);
    put_integer(frame, kStatus, message.status);
    put_integer(frame, kCounter, message.counter);
    return frame;
}

DecodeResult decode(const hal::CanFrame& frame, HandleForceTorque& message) {
    using namespace handle_force_torque;
    const DecodeResult check = check_frame(frame, kHandleForceTorqueId, kLength);
    if (check != DecodeResult::ok) {
        return check;
    }
    bool saturated = false;  // 16-bit signals at these factors always fit Q16.16
    HandleForceTorque decoded{};
    decoded.force_N = get_q16(frame, kForce, saturated);
    decoded.torque_Nmm = get_q16(frame, kTorque, saturated);
    decoded.status = get_unsigned<std::uint8_t>(frame, kStatus);
    decoded.counter = get_unsigned<std::uint8_t>(frame, kCounter);
    if (saturated) {
        return DecodeResult::out_of_range;
    }
    message = decoded;
    return DecodeResult::ok;
}

// ---- InsertionRoll ----------------------------------------------------------------------------
hal::CanFrame encode(const InsertionRoll& message) {
    using namespace insertion_roll;
    hal::CanFrame frame = start_frame(kInsertionRollId, kLength);
    put_q16(frame, kInsertion, message.insertion_mm);
    put_q16(frame, kRoll, message.roll_rad);
    put_integer(frame, kStatus, message.status);
    put_integer(frame, kCounter, message.counter);
    return frame;
}

DecodeResult decode(const hal::CanFrame& frame, InsertionRoll& message) {
    using namespace insertion_roll;
    const DecodeResult check = check_frame(frame, kInsertionRollId, kLength);
    if (check != DecodeResult::ok) {
        return check;
    }
    bool saturated = false;  // an insertion beyond ±32 m does not fit Q16.16
    InsertionRoll decoded{};
    decoded.insertion_mm = get_q16(frame, kInsertion, saturated);
    decoded.roll_rad = get_q16(frame, kRoll, saturated);
    decoded.status = get_unsigned<std::uint8_t>(frame, kStatus);
    decoded.counter = get_unsigned<std::uint8_t>(frame, kCounter);
    if (saturated) {
        return DecodeResult::out_of_range;
    }
    message = decoded;
    return DecodeResult::ok;
}

// ---- BoxStatus --------------------------------------------------------------------------------
hal::CanFrame encode(const BoxStatus& message) {
    using namespace box_status;
    hal::CanFrame frame = start_frame(kBoxStatusId, kLength);
    put_integer(frame, kHeartbeat, message.heartbeat);
    put_integer(frame, kState, static_cast<std::uint8_t>(message.state));
    put_integer(frame, kCanState, static_cast<std::uint8_t>(message.can_state));
    put_integer(frame, kKineticFaults, message.kinetic_faults);
    put_integer(frame, kDriverFaults, message.driver_faults);
    put_integer(frame, kOverruns, message.period_overruns);
    put_integer(frame, kTrackerFaults, message.tracker_faults);
    return frame;
}

DecodeResult decode(const hal::CanFrame& frame, BoxStatus& message) {
    using namespace box_status;
    const DecodeResult check = check_frame(frame, kBoxStatusId, kLength);
    if (check != DecodeResult::ok) {
        return check;
    }
    const auto state = get_unsigned<std::uint8_t>(frame, kState);
    if (state > static_cast<std::uint8_t>(BoxState::no_estimate)) {
        return DecodeResult::out_of_range;
    }
    BoxStatus decoded{};
    decoded.heartbeat = get_unsigned<std::uint8_t>(frame, kHeartbeat);
    decoded.state = static_cast<BoxState>(state);
    decoded.can_state = static_cast<CanState>(get_unsigned<std::uint8_t>(frame, kCanState));
    decoded.kinetic_faults = get_unsigned<std::uint16_t>(frame, kKineticFaults);
    decoded.driver_faults = get_unsigned<std::uint16_t>(frame, kDriverFaults);
    decoded.period_overruns = get_unsigned<std::uint8_t>(frame, kOverruns);
    decoded.tracker_faults = get_unsigned<std::uint8_t>(frame, kTrackerFaults);
    message = decoded;
    return DecodeResult::ok;
}

// ---- KineticEstimate --------------------------------------------------------------------------
hal::CanFrame encode(const KineticEstimate& message) {
    using namespace kinetic_estimate;
    hal::CanFrame frame = start_frame(kKineticEstimateId, kLength);
    put_q16(frame, kTipPath, message.tip_path_mm);
    put_q16(frame, kTipVelocity, message.tip_velocity_mm_per_s);
    put_q16(frame, kEfficiency, message.advance_efficiency);
    put_integer(frame, kValid, message.estimate_valid ? 1 : 0);
    put_integer(frame, kStale, message.inputs_stale ? 1 : 0);
    put_integer(frame, kClamped, message.depth_clamped ? 1 : 0);
    put_q16(frame, kTipUncertainty, message.tip_uncertainty_mm);
    put_integer(frame, kStep, message.step_counter);
    return frame;
}

DecodeResult decode(const hal::CanFrame& frame, KineticEstimate& message) {
    using namespace kinetic_estimate;
    const DecodeResult check = check_frame(frame, kKineticEstimateId, kLength);
    if (check != DecodeResult::ok) {
        return check;
    }
    bool saturated = false;
    KineticEstimate decoded{};
    decoded.tip_path_mm = get_q16(frame, kTipPath, saturated);
    decoded.tip_velocity_mm_per_s = get_q16(frame, kTipVelocity, saturated);
    decoded.advance_efficiency = get_q16(frame, kEfficiency, saturated);
    decoded.estimate_valid = get_flag(frame, kValid);
    decoded.inputs_stale = get_flag(frame, kStale);
    decoded.depth_clamped = get_flag(frame, kClamped);
    decoded.tip_uncertainty_mm = get_q16(frame, kTipUncertainty, saturated);
    decoded.step_counter = get_unsigned<std::uint8_t>(frame, kStep);
    if (saturated) {
        return DecodeResult::out_of_range;
    }
    message = decoded;
    return DecodeResult::ok;
}

// ---- ContactSummary ---------------------------------------------------------------------------
hal::CanFrame encode(const ContactSummary& message) {
    using namespace contact_summary;
    hal::CanFrame frame = start_frame(kContactSummaryId, kLength);
    put_q16(frame, kMaxForce, message.max_contact_force_N);
    put_q16(frame, kMaxPath, message.max_contact_path_mm);
    put_integer(frame, kMaxStation, message.max_contact_station);
    put_integer(frame, kActive, message.active_stations);
    put_integer(frame, kDistalSticking, message.distal_sticking);
    put_integer(frame, kStickingMask, message.sticking_mask);
    put_integer(frame, kStep, message.step_counter);
    return frame;
}

DecodeResult decode(const hal::CanFrame& frame, ContactSummary& message) {
    using namespace contact_summary;
    const DecodeResult check = check_frame(frame, kContactSummaryId, kLength);
    if (check != DecodeResult::ok) {
        return check;
    }
    bool saturated = false;
    ContactSummary decoded{};
    decoded.max_contact_force_N = get_q16(frame, kMaxForce, saturated);
    decoded.max_contact_path_mm = get_q16(frame, kMaxPath, saturated);
    decoded.max_contact_station = get_unsigned<std::uint8_t>(frame, kMaxStation);
    decoded.active_stations = get_unsigned<std::uint8_t>(frame, kActive);
    decoded.distal_sticking = get_unsigned<std::uint8_t>(frame, kDistalSticking);
    decoded.sticking_mask = get_unsigned<std::uint16_t>(frame, kStickingMask);
    decoded.step_counter = get_unsigned<std::uint8_t>(frame, kStep);
    if (saturated) {
        return DecodeResult::out_of_range;
    }
    message = decoded;
    return DecodeResult::ok;
}

// ---- Alarms -----------------------------------------------------------------------------------
hal::CanFrame encode(const Alarms& message) {
    using namespace alarms;
    hal::CanFrame frame = start_frame(kAlarmsId, kLength);
    put_integer(frame, kSelfLock, message.self_lock ? 1 : 0);
    put_integer(frame, kLevel, message.contact_force_level);
    put_integer(frame, kValid, message.valid ? 1 : 0);
    put_integer(frame, kTipFromModel, message.tip_from_model ? 1 : 0);
    put_integer(frame, kSelfLockRaised, message.self_lock_raised);
    put_integer(frame, kCriticalRaised, message.critical_raised);
    put_integer(frame, kStep, message.step_counter);
    return frame;
}

DecodeResult decode(const hal::CanFrame& frame, Alarms& message) {
    using namespace alarms;
    const DecodeResult check = check_frame(frame, kAlarmsId, kLength);
    if (check != DecodeResult::ok) {
        return check;
    }
    const auto level = get_unsigned<std::uint8_t>(frame, kLevel);
    if (level > 2U) {
        return DecodeResult::out_of_range;
    }
    Alarms decoded{};
    decoded.self_lock = get_flag(frame, kSelfLock);
    decoded.contact_force_level = level;
    decoded.valid = get_flag(frame, kValid);
    decoded.tip_from_model = get_flag(frame, kTipFromModel);
    decoded.self_lock_raised = get_unsigned<std::uint8_t>(frame, kSelfLockRaised);
    decoded.critical_raised = get_unsigned<std::uint8_t>(frame, kCriticalRaised);
    decoded.step_counter = get_unsigned<std::uint8_t>(frame, kStep);
    message = decoded;
    return DecodeResult::ok;
}

// ---- BoxCounters ------------------------------------------------------------------------------
hal::CanFrame encode(const BoxCounter& message) {
    using namespace box_counters;
    hal::CanFrame frame = start_frame(kBoxCountersId, kLength);
    put_integer(frame, kIndex, static_cast<std::uint8_t>(message.index));
    put_integer(frame, kValue, message.value);
    return frame;
}

DecodeResult decode(const hal::CanFrame& frame, BoxCounter& message) {
    using namespace box_counters;
    const DecodeResult check = check_frame(frame, kBoxCountersId, kLength);
    if (check != DecodeResult::ok) {
        return check;
    }
    const auto index = get_unsigned<std::uint8_t>(frame, kIndex);
    if (index >= kBoxCounterCount) {
        return DecodeResult::out_of_range;
    }
    message.index = static_cast<BoxCounterIndex>(index);
    message.value = get_unsigned<std::uint32_t>(frame, kValue);
    return DecodeResult::ok;
}

// ---- EstimateEvidence -------------------------------------------------------------------------
hal::CanFrame encode(const EstimateEvidence& message) {
    using namespace estimate_evidence;
    hal::CanFrame frame = start_frame(kEstimateEvidenceId, kLength);
    put_q16(frame, kForceUncertainty, message.max_contact_force_uncertainty_N);
    put_q16(frame, kLoopScore, message.loop_score);
    put_q16(frame, kLogRatio, message.model_log_likelihood_ratio);
    put_integer(frame, kModelSelfLock, message.model_self_lock ? 1 : 0);
    put_integer(frame, kTipFromTracker, message.tip_from_tracker ? 1 : 0);
    put_integer(frame, kStep, message.step_counter);
    return frame;
}

DecodeResult decode(const hal::CanFrame& frame, EstimateEvidence& message) {
    using namespace estimate_evidence;
    const DecodeResult check = check_frame(frame, kEstimateEvidenceId, kLength);
    if (check != DecodeResult::ok) {
        return check;
    }
    bool saturated = false;
    EstimateEvidence decoded{};
    decoded.max_contact_force_uncertainty_N = get_q16(frame, kForceUncertainty, saturated);
    decoded.loop_score = get_q16(frame, kLoopScore, saturated);
    decoded.model_log_likelihood_ratio = get_q16(frame, kLogRatio, saturated);
    decoded.model_self_lock = get_flag(frame, kModelSelfLock);
    decoded.tip_from_tracker = get_flag(frame, kTipFromTracker);
    decoded.step_counter = get_unsigned<std::uint8_t>(frame, kStep);
    if (saturated) {
        return DecodeResult::out_of_range;
    }
    message = decoded;
    return DecodeResult::ok;
}

// ---- StationForces ----------------------------------------------------------------------------
hal::CanFrame encode(const StationForces& message) {
    using namespace station_forces;
    hal::CanFrame frame = start_frame(kStationForcesId, kLength);
    put_integer(frame, kStation, message.station);
    put_integer(frame, kState, message.state);
    put_q16(frame, kNormal, message.normal_force_N);
    put_q16(frame, kTangential, message.tangential_force_N);
    put_q16(frame, kPath, message.path_mm);
    put_q16(frame, kArc, message.arc_from_tip_mm);
    return frame;
}

DecodeResult decode(const hal::CanFrame& frame, StationForces& message) {
    using namespace station_forces;
    const DecodeResult check = check_frame(frame, kStationForcesId, kLength);
    if (check != DecodeResult::ok) {
        return check;
    }
    bool saturated = false;
    StationForces decoded{};
    decoded.station = get_unsigned<std::uint8_t>(frame, kStation);
    decoded.state = get_unsigned<std::uint8_t>(frame, kState);
    decoded.normal_force_N = get_q16(frame, kNormal, saturated);
    decoded.tangential_force_N = get_q16(frame, kTangential, saturated);
    decoded.path_mm = get_q16(frame, kPath, saturated);
    decoded.arc_from_tip_mm = get_q16(frame, kArc, saturated);
    if (saturated) {
        return DecodeResult::out_of_range;
    }
    message = decoded;
    return DecodeResult::ok;
}

}  // namespace scopekin::protocol
