// reopening_serial_port.cpp — see reopening_serial_port.hpp.
#include "hal/posix_serial/reopening_serial_port.hpp"

#include <cstdio>
#include <cstring>

namespace scopekin::hal {

namespace {

void add_counters(SerialCounters& sum, const SerialCounters& more) noexcept {
    sum.bytes_received += more.bytes_received;
    sum.bytes_sent += more.bytes_sent;
    sum.overruns += more.overruns;
    sum.backend_errors += more.backend_errors;
}

}  // namespace

bool ReopeningSerialPort::open(const char* path, std::uint32_t baud_bps,
                               std::uint32_t retry_interval_us, std::span<char> error) noexcept {
    close();
    previous_sessions_ = {};
    reopen_counters_ = {};
    last_reopen_error_[0] = '\0';
    if (path != nullptr && std::strlen(path) > kMaxPathLength) {
        if (!error.empty()) {
            std::snprintf(error.data(), error.size(),
                          "cannot open serial port: its path has more than %u characters",
                          static_cast<unsigned>(kMaxPathLength));
        }
        return false;
    }
    if (!port_.open(path, baud_bps, error)) {
        return false;
    }
    std::memcpy(path_.data(), path, std::strlen(path) + 1U);  // fits: checked above
    configured_ = true;
    baud_bps_ = baud_bps;
    retry_interval_us_ = retry_interval_us == 0U ? kDefaultRetryIntervalUs : retry_interval_us;
    return true;
}

void ReopeningSerialPort::close() noexcept {
    if (port_.is_open()) {
        add_counters(previous_sessions_, port_.counters());
        port_.close();
    }
    configured_ = false;
    baud_bps_ = 0;
    path_[0] = '\0';
}

SerialCounters ReopeningSerialPort::counters() const {
    SerialCounters sum = previous_sessions_;
    if (port_.is_open()) {
        add_counters(sum, port_.counters());
    }
    return sum;
}

void ReopeningSerialPort::on_hangup() noexcept {
    add_counters(previous_sessions_, port_.counters());
    port_.close();
    ++reopen_counters_.hangups;
    // The device has just gone: the first attempt one interval later.
    next_attempt_us_ = clock_->now_us() + retry_interval_us_;
}

bool ReopeningSerialPort::ensure_open() noexcept {
    if (port_.is_open()) {
        return true;
    }
    if (!configured_) {
        return false;
    }
    const std::uint64_t now_us = clock_->now_us();
    if (now_us < next_attempt_us_) {
        return false;
    }
    next_attempt_us_ = now_us + retry_interval_us_;
    ++reopen_counters_.reopen_attempts;
    if (!port_.open(path_.data(), baud_bps_, last_reopen_error_)) {
        return false;
    }
    ++reopen_counters_.reopens;
    return true;
}

SerialTransfer ReopeningSerialPort::read(std::span<std::uint8_t> buffer, std::uint32_t timeout_us) {
    if (!ensure_open()) {
        return {configured_ ? SerialStatus::closed : SerialStatus::failed, 0};
    }
    const SerialTransfer transfer = port_.read(buffer, timeout_us);
    if (transfer.status == SerialStatus::closed) {
        on_hangup();
    }
    return transfer;
}

SerialTransfer ReopeningSerialPort::write(std::span<const std::uint8_t> bytes,
                                          std::uint32_t timeout_us) {
    if (!ensure_open()) {
        return {configured_ ? SerialStatus::closed : SerialStatus::failed, 0};
    }
    const SerialTransfer transfer = port_.write(bytes, timeout_us);
    if (transfer.status == SerialStatus::closed) {
        on_hangup();
    }
    return transfer;
}

}  // namespace scopekin::hal
