// serial_port.hpp — a byte stream (UART, USB-serial, pseudo-terminal) as the firmware sees it.
//
// Backends: hal/posix_serial (termios, raw mode), hal/loopback (in memory, simulated time),
// hal/bare_metal (the Cortex-M's UART, polled).  Timeouts in microseconds; 0 = poll.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace scopekin::hal {

enum class SerialStatus : std::uint8_t {
    ok,       ///< count bytes transferred (may be fewer than asked)
    timeout,  ///< nothing transferred within the timeout
    closed,   ///< the other end went away (hang-up, EOF); reopening is the caller's business
    failed,   ///< any other backend error (counted in SerialCounters::backend_errors)
};

struct SerialTransfer {
    SerialStatus status{SerialStatus::timeout};
    std::size_t count{0};
};

struct SerialCounters {
    std::uint32_t bytes_received{0};
    std::uint32_t bytes_sent{0};
    std::uint32_t overruns{0};  ///< bytes lost by the receiver (UART overrun), if known
    std::uint32_t backend_errors{0};
};

class SerialPort {
public:
    /// Reads up to buffer.size() bytes that are available, waiting at most `timeout_us` for the
    /// first one.
    virtual SerialTransfer read(std::span<std::uint8_t> buffer, std::uint32_t timeout_us) = 0;
    /// Writes as many of `bytes` as fit within `timeout_us`.
    virtual SerialTransfer write(std::span<const std::uint8_t> bytes, std::uint32_t timeout_us) = 0;
    /// Line rate in bit/s (as opened; a pseudo-terminal reports what was asked for).
    [[nodiscard]] virtual std::uint32_t baud() const = 0;
    [[nodiscard]] virtual SerialCounters counters() const = 0;

protected:
    SerialPort() = default;
    ~SerialPort() = default;
    SerialPort(const SerialPort&) = default;
    SerialPort& operator=(const SerialPort&) = default;
};

}  // namespace scopekin::hal
