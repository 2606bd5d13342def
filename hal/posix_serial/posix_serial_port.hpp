// posix_serial_port.hpp — hal::SerialPort on a POSIX terminal device (USB-serial adapter, UART,
// pseudo-terminal), hosted presets only.
//
// The device is opened O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC and put in raw mode
// (cfmakeraw: 8N1, no echo, no line editing, no CR/LF or flow-control translation; CLOCAL |
// CREAD; VMIN = VTIME = 0).  Timeouts are done with ppoll() on the non-blocking descriptor, at
// microsecond resolution; EINTR is retried with the remaining time.  A hang-up (EOF, EIO, ENXIO,
// ENODEV, POLLHUP — what a pseudo-terminal's slave sees when its master closes, or a USB adapter
// that is unplugged) reads as SerialStatus::closed; reopening is the caller's business
// (ReopeningSerialPort, reopening_serial_port.hpp, does it).
//
// No exceptions: open() reports failure as false plus a message that names the device and the
// errno text (e.g. "cannot open /dev/ttyUSB0: No such file or directory").  Not firmware (it is
// the Linux box's backend), but built with the strict warning set like everything else.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "hal/serial_port.hpp"

namespace scopekin::hal {

class PosixSerialPort final : public SerialPort {
public:
    /// Line rates open() accepts (the standard termios Bxxx rates this system defines), bit/s,
    /// ascending.
    [[nodiscard]] static std::span<const std::uint32_t> supported_bauds() noexcept;

    PosixSerialPort() noexcept = default;  ///< closed; open() it
    ~PosixSerialPort();
    PosixSerialPort(PosixSerialPort&& other) noexcept;
    PosixSerialPort& operator=(PosixSerialPort&& other) noexcept;
    PosixSerialPort(const PosixSerialPort&) = delete;
    PosixSerialPort& operator=(const PosixSerialPort&) = delete;

    /// Opens `path` (closing whatever was open) in raw mode at `baud_bps` (one of
    /// supported_bauds(); the settings are read back, so a device or emulator that silently keeps
    /// another speed is an error too) and discards anything already queued on it.  On failure returns false,
    /// leaves the port closed and writes a NUL-terminated message naming the device and the cause
    /// into `error` (truncated to fit; nothing written if error is empty).
    [[nodiscard]] bool open(const char* path, std::uint32_t baud_bps,
                            std::span<char> error) noexcept;
    /// Closes the device (no-op if closed); baud() reads 0 afterwards.  The destructor calls it.
    void close() noexcept;
    [[nodiscard]] bool is_open() const noexcept { return fd_ >= 0; }
    /// The file descriptor (-1 when closed), e.g. for the caller's own poll().
    [[nodiscard]] int native_handle() const noexcept { return fd_; }

    /// ok: 1..buffer.size() bytes; timeout: nothing within timeout_us (0 = do not wait); closed:
    /// hang-up / EOF; failed: any other error, or the port is not open (counted in backend_errors).
    /// An empty buffer returns ok with count 0 at once.
    SerialTransfer read(std::span<std::uint8_t> buffer, std::uint32_t timeout_us) override;
    /// Writes as much as the device takes within timeout_us: ok with the count written (possibly
    /// fewer than asked), timeout if nothing could be written, closed on hang-up, failed otherwise.
    SerialTransfer write(std::span<const std::uint8_t> bytes, std::uint32_t timeout_us) override;
    [[nodiscard]] std::uint32_t baud() const override { return baud_bps_; }
    /// overruns stays 0: termios does not report the UART's overruns.
    [[nodiscard]] SerialCounters counters() const override { return counters_; }

private:
    /// Waits until the device is ready for `events` (POLLIN / POLLOUT) or reports a hang-up, at
    /// most until `deadline_ns` (CLOCK_MONOTONIC); EINTR retried.  ok = ready (`hang_up` says
    /// whether POLLHUP was among the events), timeout, or failed (POLLNVAL, ppoll error).
    [[nodiscard]] SerialStatus wait_for(short events, std::int64_t deadline_ns,
                                        bool& hang_up) noexcept;

    int fd_{-1};
    std::uint32_t baud_bps_{0};
    SerialCounters counters_{};
};

}  // namespace scopekin::hal
