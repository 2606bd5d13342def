// reopening_serial_port.hpp — hal::SerialPort on a POSIX terminal device that survives the device
// going away: an unplugged USB-serial adapter, a pseudo-terminal whose master closed.
//
// It holds a PosixSerialPort and the device's path.  When a read or write reports a hang-up
// (SerialStatus::closed: EOF after POLLHUP, EIO, ENXIO, ENODEV) it closes the descriptor at once
// (so the kernel can release the device: a replugged adapter then gets its old name back) and
// from then on answers every read and write with `closed`, without touching the system, except
// that at most once per retry interval it tries to open the same path again (same baud rate,
// raw mode).  The first successful open ends the outage; the next read returns the device's
// bytes.  Give a path that names the device across replugs (a udev link such as
// /dev/serial/by-id/usb-..., or any symlink that is re-pointed), not a kernel name that may
// change (/dev/ttyUSB0 may come back as /dev/ttyUSB1).
//
// What the caller sees: `closed` in every call while the device is gone (the EM tracker driver
// counts it and flags kEmFaultSerial, BoxStatus.TrackerFaults' link bit, in every such period),
// and the counters below.  Bounded work: an open() attempt per retry interval, nothing in
// between.  No heap, no exceptions; the path is copied into a fixed buffer.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hal/clock.hpp"
#include "hal/posix_serial/posix_serial_port.hpp"
#include "hal/serial_port.hpp"

namespace scopekin::hal {

/// Outages of a ReopeningSerialPort since open().
struct SerialReopenCounters {
    std::uint32_t hangups{0};          ///< open -> gone transitions (hang-up, EOF, device gone)
    std::uint32_t reopen_attempts{0};  ///< open() calls while the device was gone
    std::uint32_t reopens{0};          ///< successful ones (outages that ended)
};

class ReopeningSerialPort final : public SerialPort {
public:
    /// Longest device path accepted (bytes, without the terminating NUL).
    static constexpr std::size_t kMaxPathLength = 511;
    /// Retry interval used when open() is given 0.
    static constexpr std::uint32_t kDefaultRetryIntervalUs = 100'000;

    /// `clock` times the retries (the box's monotonic clock); it must outlive the port.
    explicit ReopeningSerialPort(const MonotonicClock& clock) noexcept : clock_(&clock) {}
    ReopeningSerialPort(const ReopeningSerialPort&) = delete;
    ReopeningSerialPort& operator=(const ReopeningSerialPort&) = delete;
    ~ReopeningSerialPort() = default;

    /// Opens `path` at `baud_bps` (see PosixSerialPort::open); on success remembers both for the
    /// reopens, which are tried at most once per `retry_interval_us` (0: the default, 100 ms).
    /// On failure returns false with the message in `error`, like PosixSerialPort::open (a path
    /// longer than kMaxPathLength is refused too).  Resets every counter.
    [[nodiscard]] bool open(const char* path, std::uint32_t baud_bps,
                            std::uint32_t retry_interval_us, std::span<char> error) noexcept;
    /// Closes the device and forgets the path (no more reopens).
    void close() noexcept;

    /// The device's answer; `closed` while it is gone (after trying to reopen it if the retry
    /// interval has passed since the last attempt).
    SerialTransfer read(std::span<std::uint8_t> buffer, std::uint32_t timeout_us) override;
    SerialTransfer write(std::span<const std::uint8_t> bytes, std::uint32_t timeout_us) override;
    /// The configured rate (also while the device is gone; 0 before open()).
    [[nodiscard]] std::uint32_t baud() const override { return baud_bps_; }
    /// Summed over every time the device was open.
    [[nodiscard]] SerialCounters counters() const override;

    /// True while the device is open (false during an outage).
    [[nodiscard]] bool device_open() const noexcept { return port_.is_open(); }
    [[nodiscard]] const SerialReopenCounters& reopen_counters() const noexcept {
        return reopen_counters_;
    }
    /// Why the last reopen attempt failed ("" if none failed yet), NUL-terminated.
    [[nodiscard]] const char* last_reopen_error() const noexcept {
        return last_reopen_error_.data();
    }

private:
    /// The device reported a hang-up: close it and start the retry schedule.
    void on_hangup() noexcept;
    /// Tries to reopen if the device is gone and the retry interval has passed; true if open.
    bool ensure_open() noexcept;

    const MonotonicClock* clock_;
    PosixSerialPort port_{};
    std::array<char, kMaxPathLength + 1U> path_{};
    bool configured_{false};
    std::uint32_t baud_bps_{0};
    std::uint32_t retry_interval_us_{kDefaultRetryIntervalUs};
    std::uint64_t next_attempt_us_{0};
    SerialCounters previous_sessions_{};  ///< counters of the descriptors closed so far
    SerialReopenCounters reopen_counters_{};
    std::array<char, 256> last_reopen_error_{};
};

}  // namespace scopekin::hal
