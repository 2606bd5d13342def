// handle_sensors.cpp — see handle_sensors.hpp.
#include "drivers/handle_sensors.hpp"

namespace scopekin::drivers {

namespace {
constexpr std::uint8_t kCounterModulo = 16;  // 4-bit rolling counters
}  // namespace

using namespace messages;  // the BoxFault bits this driver sets

void HandleSensors::note_counter(Channel& channel, std::uint8_t counter) {
    if (channel.counter_known) {
        const auto expected =
            static_cast<std::uint8_t>((channel.last_counter + 1U) % kCounterModulo);
        if (counter != expected) {
            counters_.counter_gaps +=
                static_cast<std::uint32_t>((counter + kCounterModulo - expected) % kCounterModulo);
            pending_faults_ |= kBoxFaultCounterGap;
        }
    }
    channel.counter_known = true;
    channel.last_counter = counter;
}

bool HandleSensors::accept(const hal::ReceivedCanFrame& received) {
    const hal::CanFrame& frame = received.frame;
    if (frame.error || frame.remote || frame.extended) {
        return false;
    }
    protocol::DecodeResult result = protocol::DecodeResult::wrong_id;
    Channel* channel = nullptr;
    std::uint8_t status = 0;
    std::uint8_t counter = 0;
    if (frame.id == protocol::kHandleForceTorqueId) {
        protocol::HandleForceTorque message{};
        result = protocol::decode(frame, message);
        channel = &force_torque_;
        if (result == protocol::DecodeResult::ok) {
            status = message.status;
            counter = message.counter;
            if (status == 0U) {
                force_torque_sample_ = {message.force_N, message.torque_Nmm, received.timestamp_us};
                ++counters_.force_torque_samples;
            }
        }
    } else if (frame.id == protocol::kInsertionRollId) {
        protocol::InsertionRoll message{};
        result = protocol::decode(frame, message);
        channel = &insertion_roll_;
        if (result == protocol::DecodeResult::ok) {
            status = message.status;
            counter = message.counter;
            if (status == 0U) {
                insertion_roll_sample_ = {message.insertion_mm, message.roll_rad,
                                          received.timestamp_us};
                ++counters_.insertion_roll_samples;
            }
        }
    } else {
        return false;
    }
    switch (result) {
        case protocol::DecodeResult::ok:
            note_counter(*channel, counter);
            if (status != 0U) {
                ++counters_.sensor_status;
                pending_faults_ |= kBoxFaultSensorStatus;
            } else {
                channel->seen = true;
                channel->fresh = true;
                channel->last_sample_us = received.timestamp_us;
            }
            break;
        case protocol::DecodeResult::bad_length:
            ++counters_.bad_length;
            pending_faults_ |= kBoxFaultBadLength;
            break;
        case protocol::DecodeResult::out_of_range:
        case protocol::DecodeResult::wrong_id:
        case protocol::DecodeResult::not_data:
            ++counters_.out_of_range;
            pending_faults_ |= kBoxFaultOutOfRange;
            break;
    }
    return true;
}

void HandleSensors::update_staleness(Channel& channel, std::uint64_t now_us,
                                     std::uint16_t stale_bit) {
    // A receive timestamp after `now_us` (clock domains differ by a few µs) counts as age 0.
    const bool stale = !channel.seen || (now_us > channel.last_sample_us &&
                                         now_us - channel.last_sample_us > config_.stale_after_us);
    if (stale && !channel.stale) {
        ++counters_.stale_events;
        channel.counter_known = false;  // frames lost while stale are not a counter gap
    }
    channel.stale = stale;
    if (stale) {
        faults_ |= stale_bit;
    }
}

bool HandleSensors::take_fresh(Channel& channel, std::uint64_t now_us) {
    if (!channel.fresh) {
        return false;
    }
    channel.fresh = false;
    // A receive time after `now_us` (clock domains differ by a few µs) counts as age 0.
    const bool late = now_us > channel.last_sample_us &&
                      now_us - channel.last_sample_us > config_.max_sample_age_us;
    if (late) {
        ++counters_.late_samples;
        faults_ |= kBoxFaultReceiveBacklog;
    }
    return !late;
}

HandleSamples HandleSensors::take_samples(std::uint64_t now_us) {
    faults_ = pending_faults_;
    pending_faults_ = 0;
    update_staleness(force_torque_, now_us, kBoxFaultForceTorqueStale);
    update_staleness(insertion_roll_, now_us, kBoxFaultEncoderStale);

    HandleSamples samples{};
    samples.force_torque = force_torque_sample_;
    samples.insertion_roll = insertion_roll_sample_;
    samples.force_torque_fresh = take_fresh(force_torque_, now_us);
    samples.insertion_roll_fresh = take_fresh(insertion_roll_, now_us);
    return samples;
}

}  // namespace scopekin::drivers
