// recording_can_bus.cpp — see recording_can_bus.hpp.
#include "hal/linux/recording_can_bus.hpp"

#include <array>
#include <cerrno>
#include <cstring>

#include "hal/linux/linux_clock.hpp"

namespace scopekin::hal {

namespace {
constexpr std::uint64_t kFlushEveryUs = 1000000;
}  // namespace

RecordingCanBus::~RecordingCanBus() {
    (void)close();
}

bool RecordingCanBus::open(const std::string& path, const std::string& interface,
                           std::string& error) {
    (void)close();
    file_ = std::fopen(path.c_str(), "w");
    if (file_ == nullptr) {
        error = "cannot write the CAN record '" + path + "': " + std::strerror(errno);
        return false;
    }
    set_candump_interface(record_, interface);
    realtime_offset_us_ =
        static_cast<std::int64_t>(realtime_now_us()) - static_cast<std::int64_t>(clock_->now_us());
    last_flush_us_ = clock_->now_us();
    return true;
}

bool RecordingCanBus::close() {
    if (file_ == nullptr) {
        return write_errors_ == 0U;
    }
    if (std::fclose(file_) != 0) {
        ++write_errors_;
    }
    file_ = nullptr;
    return write_errors_ == 0U;
}

void RecordingCanBus::record(const CanFrame& frame, std::uint64_t monotonic_us) {
    if (file_ == nullptr) {
        return;
    }
    record_.frame = frame;
    record_.timestamp_us =
        static_cast<std::uint64_t>(static_cast<std::int64_t>(monotonic_us) + realtime_offset_us_);
    std::array<char, kCandumpLineCapacity> line{};
    const std::size_t length = format_candump_line(record_, line);
    if (length == 0U || std::fwrite(line.data(), 1, length, file_) != length) {
        ++write_errors_;
        return;
    }
    ++lines_;
    if (monotonic_us - last_flush_us_ >= kFlushEveryUs) {
        if (std::fflush(file_) != 0) {
            ++write_errors_;
        }
        last_flush_us_ = monotonic_us;
    }
}

CanStatus RecordingCanBus::send(const CanFrame& frame, std::uint32_t timeout_us) {
    const CanStatus status = bus_->send(frame, timeout_us);
    if (status == CanStatus::ok) {
        record(frame, has_send_time_ ? send_time_us_ : clock_->now_us());
    }
    return status;
}

CanStatus RecordingCanBus::receive(ReceivedCanFrame& received, std::uint32_t timeout_us) {
    const CanStatus status = bus_->receive(received, timeout_us);
    if (status == CanStatus::ok) {
        record(received.frame, received.timestamp_us);
    }
    return status;
}

}  // namespace scopekin::hal
