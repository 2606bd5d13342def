// socketcan_bus.hpp — hal::CanBus on a Linux CAN interface (SocketCAN, CAN_RAW).
//
//   * receive filters: only the identifiers the box listens to (standard ids) reach the socket;
//     the kernel drops the rest before they cost anything;
//   * error frames: all error classes are subscribed (CAN_RAW_ERR_FILTER = CAN_ERR_MASK) and
//     delivered as CanFrame::error frames;
//   * timestamps: the kernel's receive timestamp (SO_TIMESTAMP, CLOCK_REALTIME) converted to
//     CLOCK_MONOTONIC, the clock the executive runs on, by the offset between the two clocks
//     read at receive time (µs accuracy; immune to wall-clock steps between frames);
//   * drops: SO_RXQ_OVFL — the kernel's count of frames dropped because the socket's receive
//     buffer was full — is CanCounters::dropped;
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

private:
    int socket_{-1};
    CanCounters counters_{};
};

}  // namespace scopekin::hal
