// loopback_can.hpp — an in-memory CAN bus between two endpoints (the box and the simulated
// world), deterministic and driven by simulated time.
//
// A frame sent on one endpoint is queued, time-stamped with the shared clock's time, for the
// other endpoint (never for the sender, as SocketCAN without RECV_OWN_MSGS).  Each direction is a
// fixed-capacity ring (kLoopbackCanCapacity frames): a frame sent into a full queue is lost and
// counted as `dropped` at the receiving endpoint, as a kernel socket buffer overflow would be.
// Error frames can be injected (inject_error) to exercise bus-off and error handling; a
// bus-off state set with set_bus_off() makes send() return bus_off until cleared.
// Receive filters (set_receive_filter) work as the kernel's CAN_RAW_FILTER: a data frame that
// passes none of the receiving endpoint's filters leaves the wire (the sender counts it sent)
// but never enters that endpoint's queue, so it is neither received nor dropped there (counted
// in filtered() only); error frames are never filtered.  set_filtering_supported(false) makes an
// endpoint refuse filters, as a backend without them: every frame is then received.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hal/can_bus.hpp"
#include "hal/clock.hpp"

namespace scopekin::hal {

inline constexpr std::size_t kLoopbackCanCapacity = 1024;

/// One direction of the wire: a fixed-capacity ring of time-stamped frames.
struct LoopbackCanQueue {
    std::array<ReceivedCanFrame, kLoopbackCanCapacity> frames{};
    std::size_t head{0};
    std::size_t count{0};
};

class LoopbackCanEndpoint final : public CanBus {
public:
    LoopbackCanEndpoint(const MonotonicClock& clock, LoopbackCanQueue& outgoing,
                        LoopbackCanQueue& incoming)
        : clock_(&clock), outgoing_(&outgoing), incoming_(&incoming) {}

    CanStatus send(const CanFrame& frame, std::uint32_t timeout_us) override;
    CanStatus receive(ReceivedCanFrame& received, std::uint32_t timeout_us) override;
    [[nodiscard]] CanCounters counters() const override;
    CanStatus set_receive_filter(std::span<const CanIdFilter> filters) override;

    /// Queues an error frame (classes = CanErrorClass bits, data as a controller gives it) for
    /// this endpoint to receive.
    void inject_error(std::uint32_t classes, const std::array<std::uint8_t, 8>& data = {});
    /// While set, send() refuses with bus_off (the controller is off the bus).
    void set_bus_off(bool bus_off) { bus_off_ = bus_off; }
    /// Frames waiting to be received by this endpoint.
    [[nodiscard]] std::size_t pending() const { return incoming_->count; }
    /// The endpoint at the other end, told of frames lost in its incoming queue.
    void connect(LoopbackCanEndpoint& peer) { peer_ = &peer; }
    /// Data frames held back by this endpoint's receive filter (never queued here).
    [[nodiscard]] std::uint32_t filtered() const { return filtered_; }
    /// false: set_receive_filter() refuses (failed) and clears the filter — a backend without
    /// filters, on which the box receives every frame.  Default true.
    void set_filtering_supported(bool supported) {
        filtering_supported_ = supported;
        if (!supported) {
            filter_ = CanReceiveFilter{};
        }
    }

private:
    bool push(LoopbackCanQueue& queue, const CanFrame& frame);

    const MonotonicClock* clock_;
    LoopbackCanQueue* outgoing_;
    LoopbackCanQueue* incoming_;
    LoopbackCanEndpoint* peer_{nullptr};
    CanCounters counters_{};
    CanReceiveFilter filter_{};
    std::uint32_t filtered_{0};
    bool bus_off_{false};
    bool filtering_supported_{true};
};

/// The wire: both queues and both endpoints (`box` and `world`).  Large (2 x 1024 frames): keep
/// it in static storage or on the heap of a host program, not on a small stack.
class LoopbackCanWire {
public:
    explicit LoopbackCanWire(const MonotonicClock& clock)
        : box_(clock, box_to_world_, world_to_box_), world_(clock, world_to_box_, box_to_world_) {
        box_.connect(world_);
        world_.connect(box_);
    }
    LoopbackCanWire(const LoopbackCanWire&) = delete;
    LoopbackCanWire& operator=(const LoopbackCanWire&) = delete;

    LoopbackCanEndpoint& box() { return box_; }
    LoopbackCanEndpoint& world() { return world_; }

private:
    LoopbackCanQueue box_to_world_{};
    LoopbackCanQueue world_to_box_{};
    LoopbackCanEndpoint box_;
    LoopbackCanEndpoint world_;
};

}  // namespace scopekin::hal
