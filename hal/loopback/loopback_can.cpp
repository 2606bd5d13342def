// loopback_can.cpp — see loopback_can.hpp.
#include "hal/loopback/loopback_can.hpp"

namespace scopekin::hal {

bool LoopbackCanEndpoint::push(LoopbackCanQueue& queue, const CanFrame& frame) {
    if (queue.count == kLoopbackCanCapacity) {
        return false;
    }
    const std::size_t tail = (queue.head + queue.count) % kLoopbackCanCapacity;
    queue.frames[tail] = ReceivedCanFrame{frame, clock_->now_us()};
    ++queue.count;
    return true;
}

CanStatus LoopbackCanEndpoint::send(const CanFrame& frame, std::uint32_t /*timeout_us*/) {
    if (!is_valid_can_frame(frame) || frame.error) {
        ++counters_.send_failures;
        return CanStatus::invalid;
    }
    if (bus_off_) {
        ++counters_.send_failures;
        return CanStatus::bus_off;
    }
    if (peer_ != nullptr && !peer_->filter_.passes(frame)) {
        // On a real bus the frame leaves; the receiver's filter drops it before any queue.
        ++peer_->filtered_;
    } else if (!push(*outgoing_, frame)) {
        // On a real bus the frame leaves; the receiver's buffer overflows.  Same here.
        if (peer_ != nullptr) {
            ++peer_->counters_.dropped;
        }
    }
    ++counters_.sent;
    return CanStatus::ok;
}

CanStatus LoopbackCanEndpoint::set_receive_filter(std::span<const CanIdFilter> filters) {
    if (!filtering_supported_) {
        return CanStatus::failed;
    }
    return filter_.assign(filters) ? CanStatus::ok : CanStatus::invalid;
}

CanStatus LoopbackCanEndpoint::receive(ReceivedCanFrame& received, std::uint32_t /*timeout_us*/) {
    // Simulated time does not pass while waiting: an empty queue stays empty.
    if (incoming_->count == 0) {
        return CanStatus::timeout;
    }
    received = incoming_->frames[incoming_->head];
    incoming_->head = (incoming_->head + 1U) % kLoopbackCanCapacity;
    --incoming_->count;
    count_received_frame(counters_, received.frame);
    return CanStatus::ok;
}

CanCounters LoopbackCanEndpoint::counters() const {
    return counters_;
}

void LoopbackCanEndpoint::inject_error(std::uint32_t classes,
                                       const std::array<std::uint8_t, 8>& data) {
    CanFrame frame{};
    frame.error = true;
    frame.id = classes & kCanExtendedIdMask;
    frame.length = kCanMaxLength;
    frame.data = data;
    if (!push(*incoming_, frame)) {
        ++counters_.dropped;
    }
}

}  // namespace scopekin::hal
