// socketcan_bus.hpp — hal::CanBus on a Linux CAN interface (SocketCAN, CAN_RAW).
//
//   * receive filters: only the identifiers the box listens to reach the socket (CAN_RAW_FILTER,
//     set at open() from SocketCanConfig::receive_ids or later by set_receive_filter(), which
//     the executive calls at init with its drivers' identifiers); the kernel drops the rest
//     before they reach the socket's buffer, so a flood of foreign frames costs the box nothing;
//     remote frames never pass, error frames always do;
//   * error frames: all error classes are subscribed (CAN_RAW_ERR_FILTER = CAN_ERR_MASK) and
//     delivered as CanFrame::error frames;
//   * timestamps: the kernel's receive timestamp (SO_TIMESTAMP, CLOCK_REALTIME) converted to
//     CLOCK_MONOTONIC, the clock the executive runs on, by the offset between the two clocks
//     read at receive time (µs accuracy), robust to a wall-clock step while frames wait in the
//     socket (realtime_to_monotonic.hpp): the executive judges a sample's freshness by its age;
//   * drops: the kernel's count of frames dropped because the socket's receive buffer was full
//     is CanCounters::dropped, read at every receive() (SO_MEMINFO, SK_MEMINFO_DROPS), so a drop
//     is seen in the period it happened, not only when the frame queued after it is read
//     (SO_RXQ_OVFL, the same count carried by each frame, arrives behind the whole backlog);
//   * send: non-blocking write; with a timeout, waits for room (POLLOUT) and tries once more.
//     ENETDOWN (interface down, e.g. after bus-off without auto-restart) is reported as bus_off;
//     ENOBUFS (transmit queue full) as timeout.
// Opening is the only place that can fail for configuration reasons; its message names the
// interface and the system's reason.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "hal/can_bus.hpp"
#include "hal/socketcan/realtime_to_monotonic.hpp"

namespace scopekin::hal {

struct SocketCanConfig {
    std::string interface { "can0" };
    /// Standard identifiers to receive; empty = every frame.
    std::span<const std::uint32_t> receive_ids{};
    bool receive_error_frames{true};
    /// SO_RCVBUF in bytes (0: the system default).  One frame costs ~ 600-800 bytes of buffer.
    int receive_buffer_bytes{0};
};

class SocketCanBus final : public CanBus {
public:
    SocketCanBus() = default;
    ~SocketCanBus();
    SocketCanBus(const SocketCanBus&) = delete;
    SocketCanBus& operator=(const SocketCanBus&) = delete;

    /// Opens and binds the socket.  On failure returns false and a message in `error`.
    bool open(const SocketCanConfig& config, std::string& error);
    void close();
    [[nodiscard]] bool is_open() const { return socket_ >= 0; }

    CanStatus send(const CanFrame& frame, std::uint32_t timeout_us) override;
    CanStatus receive(ReceivedCanFrame& received, std::uint32_t timeout_us) override;
    [[nodiscard]] CanCounters counters() const override { return counters_; }
    /// CAN_RAW_FILTER with one kernel filter per CanIdFilter (an empty span: every frame).
    /// failed (counted in backend_errors) if the socket is not open or the kernel refuses.
    CanStatus set_receive_filter(std::span<const CanIdFilter> filters) override;

private:
    int socket_{-1};
    CanCounters counters_{};
    RealtimeToMonotonic receive_clock_{};
};

}  // namespace scopekin::hal
