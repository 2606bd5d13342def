// posix_serial_port.cpp — termios raw mode + ppoll() timeouts; see posix_serial_port.hpp.
//
// Why ppoll() before every read: in raw mode with VMIN = VTIME = 0, Linux's tty read() returns 0
// both when no byte is queued and when the line hung up, so 0 alone cannot tell "nothing yet"
// from "gone".  ppoll() can: POLLHUP is the hang-up, POLLIN with a 0-byte read and no POLLHUP is
// just a spurious wake-up.  A pseudo-terminal whose master closed answers read() with EIO (after
// the queued bytes were read): also a hang-up.
#include "hal/posix_serial/posix_serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <ctime>

namespace scopekin::hal {
namespace {

struct BaudRate {
    std::uint32_t bps;
    speed_t code;
};

// The standard termios rates; the ones above 115200 are not POSIX, hence each behind its macro.
constexpr BaudRate kBaudRates[] = {
    {50U, B50},           {75U, B75},     {110U, B110},   {134U, B134},     {150U, B150},
    {200U, B200},         {300U, B300},   {600U, B600},   {1200U, B1200},   {1800U, B1800},
    {2400U, B2400},       {4800U, B4800}, {9600U, B9600}, {19200U, B19200}, {38400U, B38400},
#ifdef B57600
    {57600U, B57600},
#endif
#ifdef B115200
    {115200U, B115200},
#endif
#ifdef B230400
    {230400U, B230400},
#endif
#ifdef B460800
    {460800U, B460800},
#endif
#ifdef B500000
    {500000U, B500000},
#endif
#ifdef B576000
    {576000U, B576000},
#endif
#ifdef B921600
    {921600U, B921600},
#endif
#ifdef B1000000
    {1000000U, B1000000},
#endif
#ifdef B1152000
    {1152000U, B1152000},
#endif
#ifdef B1500000
    {1500000U, B1500000},
#endif
#ifdef B2000000
    {2000000U, B2000000},
#endif
#ifdef B2500000
    {2500000U, B2500000},
#endif
#ifdef B3000000
    {3000000U, B3000000},
#endif
#ifdef B3500000
    {3500000U, B3500000},
#endif
#ifdef B4000000
    {4000000U, B4000000},
#endif
};

constexpr std::size_t kBaudRateCount = sizeof(kBaudRates) / sizeof(kBaudRates[0]);

constexpr std::array<std::uint32_t, kBaudRateCount> kBaudValues = [] {
    std::array<std::uint32_t, kBaudRateCount> values{};
    for (std::size_t i = 0; i < kBaudRateCount; ++i) {
        values[i] = kBaudRates[i].bps;
    }
    return values;
}();

/// Retries of a system call interrupted by a signal before it counts as a failure (a signal
/// storm must not turn a read into a hang).
constexpr int kMaxInterruptions = 1000;

[[nodiscard]] std::int64_t monotonic_ns() noexcept {
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);
    return std::int64_t{now.tv_sec} * 1'000'000'000 + now.tv_nsec;
}

// strerror_r comes in two flavours (GNU: returns char*, XSI: returns int); take either.
[[maybe_unused]] const char* strerror_result(int result, const char* buffer) noexcept {
    return result == 0 ? buffer : "unknown error";
}
[[maybe_unused]] const char* strerror_result(const char* result, const char*) noexcept {
    return result;
}

struct ErrnoText {
    std::array<char, 128> buffer{};
    const char* text{nullptr};
    explicit ErrnoText(int error) noexcept
        : text(strerror_result(::strerror_r(error, buffer.data(), buffer.size()), buffer.data())) {}
};

__attribute__((format(printf, 2, 3))) void report(std::span<char> error, const char* format,
                                                  ...) noexcept {
    if (error.empty()) {
        return;
    }
    va_list arguments;
    va_start(arguments, format);
    std::vsnprintf(error.data(), error.size(), format, arguments);
    va_end(arguments);
}

}  // namespace

std::span<const std::uint32_t> PosixSerialPort::supported_bauds() noexcept {
    return kBaudValues;
}

PosixSerialPort::~PosixSerialPort() {
    close();
}

PosixSerialPort::PosixSerialPort(PosixSerialPort&& other) noexcept
    : SerialPort(other), fd_(other.fd_), baud_bps_(other.baud_bps_), counters_(other.counters_) {
    other.fd_ = -1;
}

PosixSerialPort& PosixSerialPort::operator=(PosixSerialPort&& other) noexcept {
    if (this != &other) {
        close();
        fd_ = other.fd_;
        baud_bps_ = other.baud_bps_;
        counters_ = other.counters_;
        other.fd_ = -1;
    }
    return *this;
}

void PosixSerialPort::close() noexcept {
    if (fd_ >= 0) {
        // Not retried on EINTR: on Linux the descriptor is released even then.
        ::close(fd_);
        fd_ = -1;
    }
    baud_bps_ = 0;
}

bool PosixSerialPort::open(const char* path, std::uint32_t baud_bps,
                           std::span<char> error) noexcept {
    close();
    counters_ = {};
    if (path == nullptr || path[0] == '\0') {
        report(error, "cannot open serial port: no device path given");
        return false;
    }
    const BaudRate* rate = nullptr;
    for (const BaudRate& candidate : kBaudRates) {
        if (candidate.bps == baud_bps) {
            rate = &candidate;
        }
    }
    if (rate == nullptr) {
        report(error,
               "cannot open %s: unsupported baud rate %u bit/s (standard rates: 50 .. %u, e.g. "
               "9600, 57600, 115200, 921600)",
               path, static_cast<unsigned>(baud_bps),
               static_cast<unsigned>(kBaudValues[kBaudRateCount - 1U]));
        return false;
    }

    int fd = -1;
    for (int attempt = 0; attempt < kMaxInterruptions; ++attempt) {
        fd = ::open(path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
        if (fd >= 0 || errno != EINTR) {
            break;
        }
    }
    if (fd < 0) {
        const int open_errno = errno;
        const ErrnoText why(open_errno);
        report(error, "cannot open %s: %s (errno %d)", path, why.text, open_errno);
        return false;
    }

    termios settings{};
    if (::tcgetattr(fd, &settings) != 0) {
        const int tc_errno = errno;
        const ErrnoText why(tc_errno);
        report(error, "cannot use %s as a serial port: %s (errno %d)%s", path, why.text, tc_errno,
               tc_errno == ENOTTY ? " (not a terminal device)" : "");
        ::close(fd);
        return false;
    }
    ::cfmakeraw(&settings);  // 8 bits, no parity, no echo, no canonical mode, no translation
    settings.c_cflag |= static_cast<tcflag_t>(CLOCAL | CREAD);  // ignore modem lines, receive
    settings.c_cflag &=
        static_cast<tcflag_t>(~static_cast<tcflag_t>(CSTOPB | CRTSCTS));  // 1 stop, no RTS/CTS
    settings.c_iflag &=
        static_cast<tcflag_t>(~static_cast<tcflag_t>(IXON | IXOFF | IXANY));  // no XON/XOFF
    settings.c_cc[VMIN] = 0;  // never block in read(): timeouts are ppoll()'s
    settings.c_cc[VTIME] = 0;
    if (::cfsetispeed(&settings, rate->code) != 0 || ::cfsetospeed(&settings, rate->code) != 0 ||
        ::tcsetattr(fd, TCSANOW, &settings) != 0) {
        const int set_errno = errno;
        const ErrnoText why(set_errno);
        report(error, "cannot set %s to raw mode at %u bit/s: %s (errno %d)", path,
               static_cast<unsigned>(baud_bps), why.text, set_errno);
        ::close(fd);
        return false;
    }
    // tcsetattr succeeds if ANY change took: read back what the driver really accepted.
    termios applied{};
    if (::tcgetattr(fd, &applied) != 0 || ::cfgetospeed(&applied) != rate->code ||
        (applied.c_lflag & static_cast<tcflag_t>(ICANON | ECHO)) != 0U) {
        report(error,
               "cannot set %s to raw mode at %u bit/s: the device did not keep the settings "
               "(speed or raw mode read back differently)",
               path, static_cast<unsigned>(baud_bps));
        ::close(fd);
        return false;
    }
    ::tcflush(fd, TCIOFLUSH);  // stale bytes from before the open are not ours

    fd_ = fd;
    baud_bps_ = baud_bps;
    if (!error.empty()) {
        error[0] = '\0';
    }
    return true;
}

SerialStatus PosixSerialPort::wait_for(short events, std::int64_t deadline_ns,
                                       bool& hang_up) noexcept {
    hang_up = false;
    for (int attempt = 0; attempt < kMaxInterruptions; ++attempt) {
        const std::int64_t remaining_ns = deadline_ns - monotonic_ns();
        const std::int64_t wait_ns = remaining_ns > 0 ? remaining_ns : 0;
        timespec timeout{};
        timeout.tv_sec = static_cast<time_t>(wait_ns / 1'000'000'000);
        timeout.tv_nsec = static_cast<long>(wait_ns % 1'000'000'000);
        pollfd descriptor{fd_, events, 0};
        const int ready = ::ppoll(&descriptor, 1, &timeout, nullptr);
        if (ready > 0) {
            if ((descriptor.revents & POLLNVAL) != 0) {
                ++counters_.backend_errors;
                return SerialStatus::failed;
            }
            hang_up = (descriptor.revents & POLLHUP) != 0;
            return SerialStatus::ok;  // ready, hung up or in error: the transfer call tells which
        }
        if (ready == 0) {
            return SerialStatus::timeout;
        }
        if (errno != EINTR) {
            ++counters_.backend_errors;
            return SerialStatus::failed;
        }
    }
    ++counters_.backend_errors;
    return SerialStatus::failed;
}

SerialTransfer PosixSerialPort::read(std::span<std::uint8_t> buffer, std::uint32_t timeout_us) {
    if (fd_ < 0) {
        ++counters_.backend_errors;
        return {SerialStatus::failed, 0};
    }
    if (buffer.empty()) {
        return {SerialStatus::ok, 0};
    }
    const std::int64_t deadline_ns = monotonic_ns() + std::int64_t{timeout_us} * 1000;
    // Each pass either returns or met a spurious wake-up / EINTR; the deadline (or, with timeout
    // 0, the attempt bound) ends the loop.
    for (int attempt = 0; attempt < kMaxInterruptions; ++attempt) {
        bool hang_up = false;
        const SerialStatus readiness = wait_for(POLLIN, deadline_ns, hang_up);
        if (readiness != SerialStatus::ok) {
            return {readiness, 0};
        }
        const ssize_t count = ::read(fd_, buffer.data(), buffer.size());
        if (count > 0) {
            counters_.bytes_received += static_cast<std::uint32_t>(count);
            return {SerialStatus::ok, static_cast<std::size_t>(count)};
        }
        if (count == 0) {
            if (hang_up) {
                return {SerialStatus::closed, 0};  // EOF after a hang-up
            }
        } else if (errno == EIO || errno == ENXIO || errno == ENODEV) {
            return {SerialStatus::closed, 0};  // pseudo-terminal master closed, device gone
        } else if (errno != EINTR && errno != EAGAIN && errno != EWOULDBLOCK) {
            ++counters_.backend_errors;
            return {SerialStatus::failed, 0};
        }
        if (monotonic_ns() >= deadline_ns) {
            return {SerialStatus::timeout, 0};
        }
    }
    return {SerialStatus::timeout, 0};
}

SerialTransfer PosixSerialPort::write(std::span<const std::uint8_t> bytes,
                                      std::uint32_t timeout_us) {
    if (fd_ < 0) {
        ++counters_.backend_errors;
        return {SerialStatus::failed, 0};
    }
    const std::int64_t deadline_ns = monotonic_ns() + std::int64_t{timeout_us} * 1000;
    std::size_t written = 0;
    for (int attempt = 0; attempt < kMaxInterruptions && written < bytes.size(); ++attempt) {
        const ssize_t count = ::write(fd_, bytes.data() + written, bytes.size() - written);
        if (count > 0) {
            written += static_cast<std::size_t>(count);
            counters_.bytes_sent += static_cast<std::uint32_t>(count);
            continue;
        }
        if (count < 0 && errno == EINTR) {
            continue;
        }
        if (count < 0 && errno != EAGAIN && errno != EWOULDBLOCK) {
            const bool gone = errno == EIO || errno == EPIPE || errno == ENXIO || errno == ENODEV;
            if (written > 0U) {
                return {SerialStatus::ok, written};
            }
            if (!gone) {
                ++counters_.backend_errors;
            }
            return {gone ? SerialStatus::closed : SerialStatus::failed, 0};
        }
        // Output queue full: wait for room until the deadline.
        bool hang_up = false;
        const SerialStatus readiness = wait_for(POLLOUT, deadline_ns, hang_up);
        if (readiness == SerialStatus::timeout) {
            break;
        }
        if (readiness != SerialStatus::ok) {
            return {written > 0U ? SerialStatus::ok : readiness, written};
        }
        if (hang_up) {
            return {written > 0U ? SerialStatus::ok : SerialStatus::closed, written};
        }
    }
    if (written > 0U || bytes.empty()) {
        return {SerialStatus::ok, written};
    }
    return {SerialStatus::timeout, 0};
}

}  // namespace scopekin::hal
