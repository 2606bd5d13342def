// fuzz_handle_sensors.cpp — libFuzzer target: drivers::HandleSensors
// (firmware/drivers/handle_sensors.hpp) on any sequence of received CAN frames — any identifier,
// flags, length (0..15, beyond a CAN frame's 8 too) and data, receive times before or after the
// period's time — and any sequence of periods (take_samples) and time steps.
//
// Input: a script of operations, each an opcode byte and its operands (missing bytes read as 0):
//   0 frame   a raw frame: selector (bit 0: 0x110 / 0x111; bit 7: any 11-bit id from 2 more
//             bytes; bits 1..3 with bit 6: extended, remote, error), length & 15, 8 data bytes
//   1 sample  a well-formed 0x110 (opcode bit 3 clear) or 0x111 frame from raw values (force,
//             torque / insertion, roll; status; counter — opcode bit 4: the expected next counter,
//             bit 5: status 0)
//   2 period  take_samples(now); now advances by 2 operand bytes << (opcode bits 3..5) µs
//   3 time    frames are stamped up to 255 * 64 µs later (operand) or, opcode bit 3, that much
//             before `now` (a receive clock behind the period clock)
//
// Oracles (__builtin_trap() on violation, on top of ASan/UBSan):
//   * accept() is true exactly for standard data frames 0x110 / 0x111; each accepted frame adds
//     one to exactly one of force_torque_samples, insertion_roll_samples, bad_length,
//     out_of_range, sensor_status; a frame not accepted changes no counter; counters never
//     decrease;
//   * the held sample of each sensor is the last valid frame's (values and receive time);
//     a rejected frame never changes it;
//   * faults() after a period: only the driver's bits; bad length / out of range / sensor status
//     / counter gap exactly when that counter grew in the period; a sensor's stale bit exactly
//     when it has no valid sample or its last one is older than stale_after_us;
//   * fresh exactly when a valid sample arrived since the last period and it is at most
//     max_sample_age_us old; a newer sample that is older is late: counted in late_samples and
//     flagged kBoxFaultReceiveBacklog — nothing stale or late is reported fresh.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <span>

#include "drivers/handle_sensors.hpp"
#include "fuzz_support.hpp"
#include "messages/box_faults.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace {

namespace protocol = scopekin::protocol;
using scopekin::drivers::HandleSensorCounters;
using scopekin::drivers::HandleSensors;
using namespace scopekin::messages;

using scopekin::fuzz::Script;

constexpr std::uint16_t kDriverFaults =
    kBoxFaultForceTorqueStale | kBoxFaultEncoderStale | kBoxFaultBadLength | kBoxFaultOutOfRange |
    kBoxFaultSensorStatus | kBoxFaultCounterGap | kBoxFaultReceiveBacklog;

/// What the driver must hold for one sensor, kept from the frames it accepted.
struct Expected {
    bool seen = false;
    bool new_since_period = false;
    std::uint64_t last_us = 0;
    scopekin::fixed_point::Q16_16 first{};   // force / insertion
    scopekin::fixed_point::Q16_16 second{};  // torque / roll
};

std::uint64_t accounted(const HandleSensorCounters& c) {
    return std::uint64_t{c.force_torque_samples} + c.insertion_roll_samples + c.bad_length +
           c.out_of_range + c.sensor_status;
}

void check_grow(const HandleSensorCounters& a, const HandleSensorCounters& b) {
    require(b.force_torque_samples >= a.force_torque_samples);
    require(b.insertion_roll_samples >= a.insertion_roll_samples);
    require(b.bad_length >= a.bad_length && b.out_of_range >= a.out_of_range);
    require(b.sensor_status >= a.sensor_status && b.counter_gaps >= a.counter_gaps);
    require(b.stale_events >= a.stale_events && b.late_samples >= a.late_samples);
}

bool is_stale(const Expected& e, std::uint64_t now_us, std::uint32_t stale_after_us) {
    return !e.seen || (now_us > e.last_us && now_us - e.last_us > stale_after_us);
}

/// One sensor at a period: stale bit, freshness, lateness.  Returns true if it was late.
bool check_period_sensor(Expected& e, bool fresh, bool stale_bit, std::uint64_t now_us,
                         const scopekin::drivers::HandleSensorConfig& config) {
    require(stale_bit == is_stale(e, now_us, config.stale_after_us));
    const bool late =
        e.new_since_period && now_us > e.last_us && now_us - e.last_us > config.max_sample_age_us;
    require(fresh == (e.new_since_period && !late));
    if (fresh) require(!stale_bit || config.stale_after_us < config.max_sample_age_us);
    e.new_since_period = false;
    return late;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Script script{data, size};
    const scopekin::drivers::HandleSensorConfig config{};
    HandleSensors driver{config};
    Expected force_torque;
    Expected insertion_roll;
    std::uint64_t now_us = 1'000'000;
    std::uint64_t frame_offset_us = 0;
    bool frame_behind = false;
    std::array<std::uint8_t, 2> next_counter{};  // of the well-formed 0x110 / 0x111 frames
    HandleSensorCounters at_period = driver.counters();

    std::size_t operations = 0;
    while (!script.done() && operations < 1024) {  // bound: 1024 operations
        ++operations;
        const std::uint8_t opcode = script.byte();
        const HandleSensorCounters before = driver.counters();
        switch (opcode & 3U) {
            case 0:
            case 1: {
                scopekin::hal::ReceivedCanFrame received{};
                scopekin::hal::CanFrame& frame = received.frame;
                if ((opcode & 3U) == 0U) {
                    const std::uint8_t selector = script.byte();
                    frame.id = (selector & 0x80U) != 0U
                                   ? (script.u16() & 0x7FFU)
                                   : protocol::kHandleForceTorqueId + (selector & 1U);
                    if ((selector & 0x40U) != 0U) {
                        frame.extended = (selector & 0x02U) != 0U;
                        frame.remote = (selector & 0x04U) != 0U;
                        frame.error = (selector & 0x08U) != 0U;
                    }
                    frame.length = script.byte() & 15U;
                    for (auto& byte : frame.data)
                        byte = script.byte();
                } else {
                    const auto first = scopekin::fixed_point::Q16_16::from_raw(
                        static_cast<std::int32_t>(script.u32()));
                    const auto second = scopekin::fixed_point::Q16_16::from_raw(
                        static_cast<std::int32_t>(script.u32()));
                    auto status = static_cast<std::uint8_t>(script.byte() & 15U);
                    auto counter = static_cast<std::uint8_t>(script.byte() & 15U);
                    if ((opcode & 0x20U) != 0U) status = 0;
                    const std::size_t type = (opcode & 0x08U) == 0U ? 0U : 1U;
                    if ((opcode & 0x10U) != 0U) counter = next_counter[type];
                    next_counter[type] = static_cast<std::uint8_t>((counter + 1U) & 15U);
                    frame = (opcode & 0x08U) == 0U ? protocol::encode(protocol::HandleForceTorque{
                                                         first, second, status, counter})
                                                   : protocol::encode(protocol::InsertionRoll{
                                                         first, second, status, counter});
                }
                received.timestamp_us =
                    frame_behind ? (now_us > frame_offset_us ? now_us - frame_offset_us : 0U)
                                 : now_us + frame_offset_us;
                const bool ours = !frame.error && !frame.remote && !frame.extended &&
                                  (frame.id == protocol::kHandleForceTorqueId ||
                                   frame.id == protocol::kInsertionRollId);
                require(driver.accept(received) == ours);
                const HandleSensorCounters& after = driver.counters();
                check_grow(before, after);
                require(accounted(after) == accounted(before) + (ours ? 1U : 0U));
                require(after.counter_gaps == before.counter_gaps || ours);
                if (after.force_torque_samples != before.force_torque_samples) {
                    protocol::HandleForceTorque message{};
                    require(protocol::decode(frame, message) == protocol::DecodeResult::ok);
                    require(message.status == 0U);
                    force_torque = {true, true, received.timestamp_us, message.force_N,
                                    message.torque_Nmm};
                }
                if (after.insertion_roll_samples != before.insertion_roll_samples) {
                    protocol::InsertionRoll message{};
                    require(protocol::decode(frame, message) == protocol::DecodeResult::ok);
                    require(message.status == 0U);
                    insertion_roll = {true, true, received.timestamp_us, message.insertion_mm,
                                      message.roll_rad};
                }
                if (after.bad_length != before.bad_length) {
                    // scopekin.dbc: HandleForceTorque 6 bytes, InsertionRoll 7
                    require(frame.length != (frame.id == protocol::kHandleForceTorqueId ? 6U : 7U));
                }
                break;
            }
            case 2: {
                now_us += std::uint64_t{script.u16()} << ((opcode >> 3U) & 7U);
                const HandleSamples samples = driver.take_samples(now_us);
                const HandleSensorCounters& after = driver.counters();
                check_grow(before, after);
                require(accounted(after) == accounted(before));
                const std::uint16_t faults = driver.faults();
                require((faults & ~kDriverFaults) == 0U);
                require(((faults & kBoxFaultBadLength) != 0U) ==
                        (after.bad_length != at_period.bad_length));
                require(((faults & kBoxFaultOutOfRange) != 0U) ==
                        (after.out_of_range != at_period.out_of_range));
                require(((faults & kBoxFaultSensorStatus) != 0U) ==
                        (after.sensor_status != at_period.sensor_status));
                require(((faults & kBoxFaultCounterGap) != 0U) ==
                        (after.counter_gaps != at_period.counter_gaps));
                // The held samples are the last valid frames'.
                require(samples.force_torque.receive_time_us == force_torque.last_us);
                require(samples.force_torque.force_N == force_torque.first);
                require(samples.force_torque.torque_Nmm == force_torque.second);
                require(samples.insertion_roll.receive_time_us == insertion_roll.last_us);
                require(samples.insertion_roll.insertion_mm == insertion_roll.first);
                require(samples.insertion_roll.roll_rad == insertion_roll.second);
                const bool late_ft =
                    check_period_sensor(force_torque, samples.force_torque_fresh,
                                        (faults & kBoxFaultForceTorqueStale) != 0U, now_us, config);
                const bool late_ir =
                    check_period_sensor(insertion_roll, samples.insertion_roll_fresh,
                                        (faults & kBoxFaultEncoderStale) != 0U, now_us, config);
                require(after.late_samples - before.late_samples ==
                        (late_ft ? 1U : 0U) + (late_ir ? 1U : 0U));
                require(((faults & kBoxFaultReceiveBacklog) != 0U) == (late_ft || late_ir));
                at_period = after;
                break;
            }
            default: {
                frame_offset_us = std::uint64_t{script.byte()} * 64U;
                frame_behind = (opcode & 0x08U) != 0U;
                break;
            }
        }
    }
    return 0;
}
