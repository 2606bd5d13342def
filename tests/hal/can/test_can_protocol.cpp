// CAN protocol codecs (firmware/protocol/can): byte layouts worked out by hand from
// scopekin.dbc, strict decoding, saturation.  The exhaustive check against the DBC itself is
// check_dbc.py (python3-canmatrix, host); this file runs on every target.
#include <cstdint>

#include "portable_check.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
namespace protocol = scopekin::protocol;
using scopekin::hal::CanFrame;

bool bytes_are(const CanFrame& frame, std::initializer_list<std::uint8_t> expected) {
    if (frame.length != expected.size()) return false;
    std::size_t k = 0;
    for (const std::uint8_t byte : expected) {
        if (frame.data[k++] != byte) return false;
    }
    return true;
}

}  // namespace

// HandleForce 12.5 N / 0.005 = 2500 = 0x09C4; HandleTorque -100 N·mm / 0.1 = -1000 = 0xFC18;
// CellStatus 0; CellCounter 9 in bits 40..43.
SCOPEKIN_TEST(CanProtocol, HandleForceTorqueBytesByHand) {
    protocol::HandleForceTorque message{};
    message.force_N = Q16_16::from_ratio(25, 2);
    message.torque_Nmm = Q16_16::from_int(-100);
    message.counter = 9;
    const CanFrame frame = protocol::encode(message);
    SCOPEKIN_EXPECT_EQ(frame.id, 0x110U);
    SCOPEKIN_EXPECT_TRUE(!frame.extended && !frame.remote && !frame.error);
    SCOPEKIN_EXPECT_TRUE(bytes_are(frame, {0xC4, 0x09, 0x18, 0xFC, 0x00, 0x09}));
    protocol::HandleForceTorque decoded{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(frame, decoded) == protocol::DecodeResult::ok);
    SCOPEKIN_EXPECT_EQ(decoded.force_N.raw(), message.force_N.raw());
    SCOPEKIN_EXPECT_EQ(decoded.torque_Nmm.raw(), message.torque_Nmm.raw());
    SCOPEKIN_EXPECT_EQ(decoded.counter, 9);
}

// Insertion 1234.56 mm / 0.01 = 123456 = 0x01E240; Roll -1.5708 rad / 0.0001 = -15708 =
// 0xFFC2A4 in 24 bits; EncoderStatus 0 and EncoderCounter 3 share byte 6: 0x30.
SCOPEKIN_TEST(CanProtocol, InsertionRollBytesByHand) {
    protocol::InsertionRoll message{};
    message.insertion_mm = Q16_16::from_ratio(123456, 100);
    message.roll_rad = Q16_16::from_ratio(-15708, 10000);
    message.counter = 3;
    const CanFrame frame = protocol::encode(message);
    SCOPEKIN_EXPECT_EQ(frame.id, 0x111U);
    SCOPEKIN_EXPECT_TRUE(bytes_are(frame, {0x40, 0xE2, 0x01, 0xA4, 0xC2, 0xFF, 0x30}));
}

// TipPath 512.3 mm -> 5123 = 0x1403; TipVelocity -20 mm/s -> -200 = 0xFF38; efficiency 0.75 ->
// 750 = 0x02EE; EstimateValid 1, InputsStale 1 -> byte 6 = 0x03; StepCounter 0xAB.
SCOPEKIN_TEST(CanProtocol, KineticEstimateBytesByHand) {
    protocol::KineticEstimate message{};
    message.tip_path_mm = Q16_16::from_ratio(5123, 10);
    message.tip_velocity_mm_per_s = Q16_16::from_int(-20);
    message.advance_efficiency = Q16_16::from_ratio(3, 4);
    message.estimate_valid = true;
    message.inputs_stale = true;
    message.step_counter = 0xAB;
    const CanFrame frame = protocol::encode(message);
    SCOPEKIN_EXPECT_EQ(frame.id, 0x181U);
    SCOPEKIN_EXPECT_TRUE(bytes_are(frame, {0x03, 0x14, 0x38, 0xFF, 0xEE, 0x02, 0x03, 0xAB}));
}

// TipUncertainty (1.1): bits 51-55 at 10 mm. 120 mm -> 12 -> byte 6 = 12 << 3 | 0x03 = 0x63; 400 mm
// is beyond the 5 bits and saturates at 31 (310 mm) -> 0xFB. Decoding gives the 10 mm step back.
SCOPEKIN_TEST(CanProtocol, KineticEstimateTipUncertaintyBytesByHand) {
    protocol::KineticEstimate message{};
    message.estimate_valid = true;
    message.inputs_stale = true;
    message.tip_uncertainty_mm = Q16_16::from_int(120);
    CanFrame frame = protocol::encode(message);
    SCOPEKIN_EXPECT_TRUE(bytes_are(frame, {0, 0, 0, 0, 0, 0, 0x63, 0}));
    protocol::KineticEstimate decoded{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(frame, decoded) == protocol::DecodeResult::ok);
    SCOPEKIN_EXPECT_EQ(decoded.tip_uncertainty_mm.raw(), Q16_16::from_int(120).raw());
    message.tip_uncertainty_mm = Q16_16::from_int(400);
    frame = protocol::encode(message);
    SCOPEKIN_EXPECT_TRUE(bytes_are(frame, {0, 0, 0, 0, 0, 0, 0xFB, 0}));
}

// SelfLockAlarm 1 (bit 0), ContactForceLevel 2 (bits 1-2: 0b100), AlarmsValid 1 (bit 3) ->
// byte 0 = 0x0D; SelfLockRaised 3, CriticalRaised 1, StepCounter 7.
SCOPEKIN_TEST(CanProtocol, AlarmsBytesByHand) {
    protocol::Alarms message{};
    message.self_lock = true;
    message.contact_force_level = 2;
    message.valid = true;
    message.self_lock_raised = 3;
    message.critical_raised = 1;
    message.step_counter = 7;
    const CanFrame frame = protocol::encode(message);
    SCOPEKIN_EXPECT_EQ(frame.id, 0x183U);
    SCOPEKIN_EXPECT_TRUE(bytes_are(frame, {0x0D, 0x03, 0x01, 0x07}));
    // TipFromModel 1 (bit 4, added in 1.2): byte 0 = 0x1D; a 1.1 reader ignores the bit.
    message.tip_from_model = true;
    SCOPEKIN_EXPECT_TRUE(bytes_are(protocol::encode(message), {0x1D, 0x03, 0x01, 0x07}));
    protocol::Alarms decoded{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(protocol::encode(message), decoded) ==
                         protocol::DecodeResult::ok);
    SCOPEKIN_EXPECT_TRUE(decoded.tip_from_model);
}

// EstimateEvidence (1.3): MaxContactForceUncertainty 2.5 N -> 2500 = 0x09C4; LoopScore 0.8 ->
// 8000 = 0x1F40; ModelLogLikelihoodRatio -7.5 -> -750 = 0xFD12; ModelSelfLockAlarm 1 (bit 48),
// TipFromTracker 1 (bit 49): byte 6 = 0x03; StepCounter 0x5C. Decoding gives the same Q16.16 values back (each a whole number of steps).
SCOPEKIN_TEST(CanProtocol, EstimateEvidenceBytesByHand) {
    protocol::EstimateEvidence message{};
    message.max_contact_force_uncertainty_N = Q16_16::from_ratio(5, 2);
    message.loop_score = Q16_16::from_ratio(4, 5);
    message.model_log_likelihood_ratio = Q16_16::from_ratio(-15, 2);
    message.model_self_lock = true;
    message.tip_from_tracker = true;
    message.step_counter = 0x5C;
    const CanFrame frame = protocol::encode(message);
    SCOPEKIN_EXPECT_EQ(frame.id, 0x185U);
    SCOPEKIN_EXPECT_TRUE(bytes_are(frame, {0xC4, 0x09, 0x40, 0x1F, 0x12, 0xFD, 0x03, 0x5C}));
    protocol::EstimateEvidence decoded{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(frame, decoded) == protocol::DecodeResult::ok);
    SCOPEKIN_EXPECT_EQ(decoded.max_contact_force_uncertainty_N.raw(),
                       message.max_contact_force_uncertainty_N.raw());
    SCOPEKIN_EXPECT_EQ(decoded.loop_score.raw(), message.loop_score.raw());
    SCOPEKIN_EXPECT_EQ(decoded.model_log_likelihood_ratio.raw(),
                       message.model_log_likelihood_ratio.raw());
    SCOPEKIN_EXPECT_TRUE(decoded.model_self_lock);
    SCOPEKIN_EXPECT_TRUE(decoded.tip_from_tracker);
    SCOPEKIN_EXPECT_EQ(decoded.step_counter, 0x5C);
    // A force SD beyond the signal saturates at 65.535 N (0xFFFF).
    message.max_contact_force_uncertainty_N = Q16_16::from_int(100);
    SCOPEKIN_EXPECT_TRUE(
        bytes_are(protocol::encode(message), {0xFF, 0xFF, 0x40, 0x1F, 0x12, 0xFD, 0x03, 0x5C}));
}

SCOPEKIN_TEST(CanProtocol, EveryMessageRoundTrips) {
    protocol::BoxStatus status{};
    status.heartbeat = 200;
    status.state = protocol::BoxState::degraded;
    status.can_state = protocol::CanState::bus_off;
    status.kinetic_faults = 0x2A5A;
    status.driver_faults = 0x1234;
    status.period_overruns = 17;
    status.tracker_faults = 0x81;
    protocol::BoxStatus status_back{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(protocol::encode(status), status_back) ==
                         protocol::DecodeResult::ok);
    SCOPEKIN_EXPECT_EQ(status_back.heartbeat, 200);
    SCOPEKIN_EXPECT_TRUE(status_back.state == protocol::BoxState::degraded);
    SCOPEKIN_EXPECT_TRUE(status_back.can_state == protocol::CanState::bus_off);
    SCOPEKIN_EXPECT_EQ(status_back.kinetic_faults, 0x2A5A);
    SCOPEKIN_EXPECT_EQ(status_back.driver_faults, 0x1234);
    SCOPEKIN_EXPECT_EQ(status_back.period_overruns, 17);
    SCOPEKIN_EXPECT_EQ(status_back.tracker_faults, 0x81);

    protocol::ContactSummary summary{};
    summary.max_contact_force_N = Q16_16::from_ratio(12345, 1000);
    summary.max_contact_path_mm = Q16_16::from_ratio(4321, 10);
    summary.max_contact_station = 11;
    summary.active_stations = 12;
    summary.distal_sticking = 3;
    summary.sticking_mask = 0xA05;
    summary.step_counter = 255;
    protocol::ContactSummary summary_back{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(protocol::encode(summary), summary_back) ==
                         protocol::DecodeResult::ok);
    // 0.001 N and 0.1 mm steps: the Q16.16 values come back within half a step.
    const std::int32_t force_error =
        summary_back.max_contact_force_N.raw() - summary.max_contact_force_N.raw();
    SCOPEKIN_EXPECT_TRUE(force_error <= 33 && force_error >= -33);
    const std::int32_t path_error =
        summary_back.max_contact_path_mm.raw() - summary.max_contact_path_mm.raw();
    SCOPEKIN_EXPECT_TRUE(path_error <= 3277 && path_error >= -3277);
    SCOPEKIN_EXPECT_EQ(summary_back.max_contact_station, 11);
    SCOPEKIN_EXPECT_EQ(summary_back.active_stations, 12);
    SCOPEKIN_EXPECT_EQ(summary_back.sticking_mask, 0xA05);
    SCOPEKIN_EXPECT_EQ(summary_back.step_counter, 255);

    protocol::BoxCounter counter{protocol::BoxCounterIndex::counter_gaps, 0xDEADBEEFU};
    protocol::BoxCounter counter_back{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(protocol::encode(counter), counter_back) ==
                         protocol::DecodeResult::ok);
    SCOPEKIN_EXPECT_TRUE(counter_back.index == protocol::BoxCounterIndex::counter_gaps);
    SCOPEKIN_EXPECT_EQ(counter_back.value, 0xDEADBEEFU);

    protocol::StationForces station{};
    station.station = 4;
    station.state = 2;
    station.normal_force_N = Q16_16::from_int(3);
    station.tangential_force_N = Q16_16::from_ratio(3, 2);
    station.path_mm = Q16_16::from_int(600);
    station.arc_from_tip_mm = Q16_16::from_int(200);
    protocol::StationForces station_back{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(protocol::encode(station), station_back) ==
                         protocol::DecodeResult::ok);
    SCOPEKIN_EXPECT_EQ(station_back.station, 4);
    SCOPEKIN_EXPECT_EQ(station_back.state, 2);
    SCOPEKIN_EXPECT_EQ(station_back.normal_force_N.raw(), Q16_16::from_int(3).raw());
    SCOPEKIN_EXPECT_EQ(station_back.tangential_force_N.raw(), Q16_16::from_ratio(3, 2).raw());
    SCOPEKIN_EXPECT_EQ(station_back.path_mm.raw(), Q16_16::from_int(600).raw());
    SCOPEKIN_EXPECT_EQ(station_back.arc_from_tip_mm.raw(), Q16_16::from_int(200).raw());
}

SCOPEKIN_TEST(CanProtocol, DecodingIsStrict) {
    protocol::HandleForceTorque message{};
    message.force_N = Q16_16::from_int(5);
    const CanFrame good = protocol::encode(message);
    protocol::HandleForceTorque out{};
    out.force_N = Q16_16::from_int(-7);  // must stay untouched on refusal

    CanFrame wrong_length = good;
    wrong_length.length = 8;
    SCOPEKIN_EXPECT_TRUE(protocol::decode(wrong_length, out) == protocol::DecodeResult::bad_length);
    CanFrame extended = good;
    extended.extended = true;
    SCOPEKIN_EXPECT_TRUE(protocol::decode(extended, out) == protocol::DecodeResult::not_data);
    CanFrame remote = good;
    remote.remote = true;
    SCOPEKIN_EXPECT_TRUE(protocol::decode(remote, out) == protocol::DecodeResult::not_data);
    CanFrame error = good;
    error.error = true;
    SCOPEKIN_EXPECT_TRUE(protocol::decode(error, out) == protocol::DecodeResult::not_data);
    CanFrame other = good;
    other.id = 0x111;
    SCOPEKIN_EXPECT_TRUE(protocol::decode(other, out) == protocol::DecodeResult::wrong_id);
    SCOPEKIN_EXPECT_EQ(out.force_N.raw(), Q16_16::from_int(-7).raw());

    // An insertion of 83,886 mm fits the 24-bit signal but not Q16.16 (±32,768): refused.
    CanFrame far = protocol::encode(protocol::InsertionRoll{});
    far.data[0] = 0xFF;
    far.data[1] = 0xFF;
    far.data[2] = 0x7F;
    protocol::InsertionRoll insertion{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(far, insertion) == protocol::DecodeResult::out_of_range);
    // The edge: -32768.00 mm (raw -3276800 = 0xCE0000) is Q16.16's smallest value and fits;
    // one step further (0xCDFFFF) does not.
    far.data[0] = 0x00;
    far.data[1] = 0x00;
    far.data[2] = 0xCE;
    SCOPEKIN_EXPECT_TRUE(protocol::decode(far, insertion) == protocol::DecodeResult::ok);
    SCOPEKIN_EXPECT_EQ(insertion.insertion_mm.raw(), Q16_16::min().raw());
    far.data[0] = 0xFF;
    far.data[1] = 0xFF;
    far.data[2] = 0xCD;
    SCOPEKIN_EXPECT_TRUE(protocol::decode(far, insertion) == protocol::DecodeResult::out_of_range);

    // Undefined enumeration values.
    CanFrame state = protocol::encode(protocol::BoxStatus{});
    state.data[1] = 0x04;  // BoxState 4
    protocol::BoxStatus status{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(state, status) == protocol::DecodeResult::out_of_range);
    CanFrame level = protocol::encode(protocol::Alarms{});
    level.data[0] = 0x06;  // ContactForceLevel 3
    protocol::Alarms alarms{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(level, alarms) == protocol::DecodeResult::out_of_range);
    CanFrame index = protocol::encode(protocol::BoxCounter{});
    index.data[0] = 17;  // the first index the DBC does not define
    protocol::BoxCounter counter{};
    SCOPEKIN_EXPECT_TRUE(protocol::decode(index, counter) == protocol::DecodeResult::out_of_range);
}

// Encoding saturates to the signal's range: 200 N is beyond the 16-bit HandleForce (±163.84 N).
SCOPEKIN_TEST(CanProtocol, EncodingSaturatesToTheSignalRange) {
    protocol::HandleForceTorque message{};
    message.force_N = Q16_16::from_int(200);
    message.torque_Nmm = Q16_16::from_int(-5000);
    message.counter = 31;  // 4-bit counter: clamped to 15
    const CanFrame frame = protocol::encode(message);
    SCOPEKIN_EXPECT_TRUE(bytes_are(frame, {0xFF, 0x7F, 0x00, 0x80, 0x00, 0x0F}));
}

SCOPEKIN_TEST(CanProtocol, LayoutsCoverEveryMessageOnce) {
    const auto layouts = protocol::message_layouts();
    SCOPEKIN_EXPECT_EQ(layouts.size(), 9U);
    for (const auto& layout : layouts) {
        SCOPEKIN_EXPECT_TRUE(protocol::find_message_layout(layout.id) == &layout);
        for (const auto& signal : layout.signals) {
            // Every signal lies inside the message's length.
            SCOPEKIN_EXPECT_TRUE(signal.start_bit + signal.bit_length <= layout.length * 8U);
        }
    }
    SCOPEKIN_EXPECT_TRUE(protocol::find_message_layout(0x7FF) == nullptr);
}
