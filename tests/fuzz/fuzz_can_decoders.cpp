// fuzz_can_decoders.cpp — libFuzzer target: every typed decoder of the box's CAN messages
// (firmware/protocol/can/scopekin_messages.hpp) on any frame a bus or a backend could hand over.
//
// Input layout (the seed corpus, tests/fuzz/corpus/can_decoders/, is written by make_corpus.py):
//   byte 0   identifier selector: 0x00..0xBF -> the protocol's ids (selector % 9, in the order of
//            message_layouts()); 0xC0..0xFF -> the next 4 bytes, little-endian, masked to 11 bits
//            (or 29 with the extended flag) — any other id, the error-class bits of error frames
//   byte 1   bits 0..3: length 0..15 (a length beyond 8 is passed through: the decoders must
//            refuse it, not read past the data), bit 4 extended, bit 5 remote, bit 6 error frame
//   rest     up to 8 data bytes (missing ones are 0)
//
// Oracles (__builtin_trap() on violation, on top of ASan/UBSan):
//   * the result is the one the frame's kind dictates: error/remote/extended -> not_data, another
//     id -> wrong_id, a length other than the DBC's -> bad_length; out_of_range only for a
//     well-formed frame of the message;
//   * a refusal leaves the output untouched;
//   * ok: encode(x) is a standard data frame of the message's id and length, equal to the input
//     data on every bit that belongs to a signal (and 0 elsewhere), and decode(encode(x)) == x.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hal/can_bus.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace {

using scopekin::hal::CanFrame;
namespace protocol = scopekin::protocol;
using protocol::DecodeResult;

void require(bool condition) {
    if (!condition) {
        __builtin_trap();
    }
}

// ---- field-wise equality (the message structs have no operator==) ------------------------------

bool same(const protocol::HandleForceTorque& a, const protocol::HandleForceTorque& b) {
    return a.force_N == b.force_N && a.torque_Nmm == b.torque_Nmm && a.status == b.status &&
           a.counter == b.counter;
}
bool same(const protocol::InsertionRoll& a, const protocol::InsertionRoll& b) {
    return a.insertion_mm == b.insertion_mm && a.roll_rad == b.roll_rad && a.status == b.status &&
           a.counter == b.counter;
}
bool same(const protocol::BoxStatus& a, const protocol::BoxStatus& b) {
    return a.heartbeat == b.heartbeat && a.state == b.state && a.can_state == b.can_state &&
           a.kinetic_faults == b.kinetic_faults && a.driver_faults == b.driver_faults &&
           a.period_overruns == b.period_overruns && a.tracker_faults == b.tracker_faults;
}
bool same(const protocol::KineticEstimate& a, const protocol::KineticEstimate& b) {
    return a.tip_path_mm == b.tip_path_mm && a.tip_velocity_mm_per_s == b.tip_velocity_mm_per_s &&
           a.advance_efficiency == b.advance_efficiency && a.estimate_valid == b.estimate_valid &&
           a.inputs_stale == b.inputs_stale && a.depth_clamped == b.depth_clamped &&
           a.tip_uncertainty_mm == b.tip_uncertainty_mm && a.step_counter == b.step_counter;
}
bool same(const protocol::ContactSummary& a, const protocol::ContactSummary& b) {
    return a.max_contact_force_N == b.max_contact_force_N &&
           a.max_contact_path_mm == b.max_contact_path_mm &&
           a.max_contact_station == b.max_contact_station &&
           a.active_stations == b.active_stations && a.distal_sticking == b.distal_sticking &&
           a.sticking_mask == b.sticking_mask && a.step_counter == b.step_counter;
}
bool same(const protocol::Alarms& a, const protocol::Alarms& b) {
    return a.self_lock == b.self_lock && a.contact_force_level == b.contact_force_level &&
           a.valid == b.valid && a.tip_from_model == b.tip_from_model &&
           a.self_lock_raised == b.self_lock_raised && a.critical_raised == b.critical_raised &&
           a.step_counter == b.step_counter;
}
bool same(const protocol::BoxCounter& a, const protocol::BoxCounter& b) {
    return a.index == b.index && a.value == b.value;
}
bool same(const protocol::EstimateEvidence& a, const protocol::EstimateEvidence& b) {
    return a.max_contact_force_uncertainty_N == b.max_contact_force_uncertainty_N &&
           a.loop_score == b.loop_score &&
           a.model_log_likelihood_ratio == b.model_log_likelihood_ratio &&
           a.model_self_lock == b.model_self_lock && a.tip_from_tracker == b.tip_from_tracker &&
           a.step_counter == b.step_counter;
}
bool same(const protocol::StationForces& a, const protocol::StationForces& b) {
    return a.station == b.station && a.state == b.state && a.normal_force_N == b.normal_force_N &&
           a.tangential_force_N == b.tangential_force_N && a.path_mm == b.path_mm &&
           a.arc_from_tip_mm == b.arc_from_tip_mm;
}

/// A non-default value of the decoder's output (a fixed frame of the message, decoded), to see
/// that refusals leave their output alone.  The pattern is valid for every message: BoxState 3,
/// ContactForceLevel 0, CounterIndex 9, Insertion within Q16.16.
template <typename Message>
Message sentinel(std::uint32_t id, std::uint8_t length) {
    CanFrame frame{};
    frame.id = id;
    frame.length = length;
    frame.data = {0x09, 0x13, 0x05, 0x57, 0x79, 0x9B, 0xBD, 0xDF};
    Message message{};
    require(protocol::decode(frame, message) == DecodeResult::ok);
    return message;
}

/// Bits of the frame that belong to a signal of `layout`.
std::array<std::uint8_t, 8> signal_mask(const protocol::MessageLayout& layout) {
    std::array<std::uint8_t, 8> mask{};
    for (const protocol::CanSignal& signal : layout.signals) {
        for (std::uint32_t k = 0; k < signal.bit_length; ++k) {
            const std::uint32_t bit = signal.start_bit + k;
            mask[bit / 8U] = static_cast<std::uint8_t>(mask[bit / 8U] | (1U << (bit % 8U)));
        }
    }
    return mask;
}

template <typename Message>
void check(const CanFrame& frame, std::uint32_t id) {
    const protocol::MessageLayout* layout = protocol::find_message_layout(id);
    require(layout != nullptr);

    Message message = sentinel<Message>(id, layout->length);
    const Message before = message;
    const DecodeResult result = protocol::decode(frame, message);

    // The result the frame's kind dictates.
    if (frame.error || frame.remote || frame.extended) {
        require(result == DecodeResult::not_data);
    } else if (frame.id != id) {
        require(result == DecodeResult::wrong_id);
    } else if (frame.length != layout->length) {
        require(result == DecodeResult::bad_length);
    } else {
        require(result == DecodeResult::ok || result == DecodeResult::out_of_range);
    }
    if (result != DecodeResult::ok) {
        require(same(message, before));
        return;
    }

    // Round trip: the encoder gives back the input's signal bits, and decoding that gives x.
    const CanFrame encoded = protocol::encode(message);
    require(encoded.id == id && encoded.length == layout->length && !encoded.extended &&
            !encoded.remote && !encoded.error);
    const std::array<std::uint8_t, 8> mask = signal_mask(*layout);
    for (std::size_t i = 0; i < encoded.data.size(); ++i) {
        const std::uint8_t expected = i < layout->length ? frame.data[i] & mask[i] : 0U;
        require(encoded.data[i] == expected);
    }
    Message again = sentinel<Message>(id, layout->length);
    require(protocol::decode(encoded, again) == DecodeResult::ok);
    require(same(again, message));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 2U) {
        return 0;
    }
    const std::span<const std::uint8_t> input{data, size};
    const auto layouts = protocol::message_layouts();
    require(layouts.size() == 9U);

    CanFrame frame{};
    const std::uint8_t selector = input[0];
    const std::uint8_t flags = input[1];
    frame.length = static_cast<std::uint8_t>(flags & 0x0FU);
    frame.extended = (flags & 0x10U) != 0U;
    frame.remote = (flags & 0x20U) != 0U;
    frame.error = (flags & 0x40U) != 0U;
    std::size_t next = 2;
    if (selector < 0xC0U) {
        frame.id = layouts[selector % layouts.size()].id;
    } else {
        std::uint32_t id = 0;
        for (std::size_t i = 0; i < 4U && next < input.size(); ++i, ++next) {
            id |= static_cast<std::uint32_t>(input[next]) << (8U * i);
        }
        frame.id = id & (frame.extended || frame.error ? scopekin::hal::kCanExtendedIdMask
                                                       : scopekin::hal::kCanStandardIdMask);
    }
    for (std::size_t i = 0; i < frame.data.size() && next < input.size(); ++i, ++next) {
        frame.data[i] = input[next];
    }

    check<protocol::HandleForceTorque>(frame, protocol::kHandleForceTorqueId);
    check<protocol::InsertionRoll>(frame, protocol::kInsertionRollId);
    check<protocol::BoxStatus>(frame, protocol::kBoxStatusId);
    check<protocol::KineticEstimate>(frame, protocol::kKineticEstimateId);
    check<protocol::ContactSummary>(frame, protocol::kContactSummaryId);
    check<protocol::Alarms>(frame, protocol::kAlarmsId);
    check<protocol::BoxCounter>(frame, protocol::kBoxCountersId);
    check<protocol::EstimateEvidence>(frame, protocol::kEstimateEvidenceId);
    check<protocol::StationForces>(frame, protocol::kStationForcesId);
    return 0;
}
