// can_health.hpp — the CAN controller's state as its error frames tell it (error-active,
// warning, error-passive, bus-off) and what the executive reports of it.
//
// Error frames carry the classes of linux/can/error.h (hal::CanErrorClass); for controller
// problems data[1] holds the state bits (CAN_ERR_CRTL_*).  Bus-off is left when the controller
// reports a restart (kCanErrorRestarted, e.g. the kernel's restart-ms), when a controller-state
// frame reports error-active again, or when a frame is sent successfully (the controller is
// back on the bus; a received frame proves nothing: a backend may deliver frames queued before).
#pragma once

#include <cstdint>

#include "hal/can_bus.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace scopekin::executive {

class CanHealth {
public:
    /// An error frame arrived.
    void on_error_frame(const hal::CanFrame& frame);
    /// A send succeeded: the controller is on the bus.
    void on_sent();
    /// A send failed with `status`.
    void on_send_failure(hal::CanStatus status);

    [[nodiscard]] protocol::CanState state() const { return state_; }
    /// Worst state since the last call, then starts a new interval at the current state.
    [[nodiscard]] protocol::CanState take_worst_state();
    [[nodiscard]] std::uint32_t error_frames() const { return error_frames_; }
    [[nodiscard]] std::uint32_t bus_off_events() const { return bus_off_events_; }
    [[nodiscard]] std::uint32_t recoveries() const { return recoveries_; }

private:
    void enter(protocol::CanState state);

    protocol::CanState state_{protocol::CanState::error_active};
    protocol::CanState worst_{protocol::CanState::error_active};
    std::uint32_t error_frames_{0};
    std::uint32_t bus_off_events_{0};
    std::uint32_t recoveries_{0};
};

}  // namespace scopekin::executive
