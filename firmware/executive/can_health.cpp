// can_health.cpp — see can_health.hpp.
#include "executive/can_health.hpp"

namespace scopekin::executive {

namespace {
// data[1] of a controller-problem error frame (linux/can/error.h CAN_ERR_CRTL_*).
constexpr std::uint8_t kCtrlRxWarning = 0x04U;
constexpr std::uint8_t kCtrlTxWarning = 0x08U;
constexpr std::uint8_t kCtrlRxPassive = 0x10U;
constexpr std::uint8_t kCtrlTxPassive = 0x20U;
constexpr std::uint8_t kCtrlActive = 0x40U;

constexpr std::uint8_t rank(protocol::CanState state) {
    return static_cast<std::uint8_t>(state);
}
}  // namespace

void CanHealth::enter(protocol::CanState state) {
    if (state_ == protocol::CanState::bus_off && state != protocol::CanState::bus_off) {
        ++recoveries_;
    }
    if (state == protocol::CanState::bus_off && state_ != protocol::CanState::bus_off) {
        ++bus_off_events_;
    }
    state_ = state;
    if (rank(state) > rank(worst_)) {
        worst_ = state;
    }
}

void CanHealth::on_error_frame(const hal::CanFrame& frame) {
    ++error_frames_;
    const std::uint32_t classes = frame.id;
    if ((classes & hal::kCanErrorBusOff) != 0U) {
        enter(protocol::CanState::bus_off);
        return;
    }
    if ((classes & hal::kCanErrorRestarted) != 0U) {
        enter(protocol::CanState::error_active);
    }
    if ((classes & hal::kCanErrorController) != 0U && frame.length >= 2U) {
        const std::uint8_t control = frame.data[1];
        if ((control & (kCtrlRxPassive | kCtrlTxPassive)) != 0U) {
            enter(protocol::CanState::error_passive);
        } else if ((control & (kCtrlRxWarning | kCtrlTxWarning)) != 0U) {
            enter(protocol::CanState::warning);
        } else if ((control & kCtrlActive) != 0U) {
            enter(protocol::CanState::error_active);
        }
    }
    // Worst-state bookkeeping for an error frame that changed nothing.
    if (rank(state_) > rank(worst_)) {
        worst_ = state_;
    }
}

void CanHealth::on_sent() {
    if (state_ == protocol::CanState::bus_off) {
        enter(protocol::CanState::error_active);
    }
}

void CanHealth::on_send_failure(hal::CanStatus status) {
    if (status == hal::CanStatus::bus_off) {
        enter(protocol::CanState::bus_off);
    }
}

protocol::CanState CanHealth::take_worst_state() {
    const protocol::CanState worst = worst_;
    worst_ = state_;
    return worst;
}

}  // namespace scopekin::executive
