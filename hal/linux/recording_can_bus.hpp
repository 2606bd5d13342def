// recording_can_bus.hpp — a hal::CanBus that passes everything through to another one and writes
// every frame it sees (received, error frames included, and sent) to a candump log file, so the
// traffic can be replayed with can-utils' `canplayer` or `scopekin replay`.
//
// Timestamps are wall-clock (CLOCK_REALTIME) microseconds, as candump writes them: a received
// frame's monotonic timestamp is converted with the realtime-monotonic offset read at open().
// A sent frame carries the time given to set_send_time_us() — main passes each period's release
// time, the `now` the box ran that period at — so `scopekin replay` can run every period at the
// time, and on the frames, the box did (the received frames of a period are the lines before its
// first sent frame). Without it a sent frame carries the clock at send().
// The file is flushed once a second and at close(); a write error is counted, reported by
// write_errors(), and recording goes on (the box's work does not stop for its log).
#pragma once

#include <cstdint>
#include <cstdio>
#include <span>
#include <string>

#include "hal/can_bus.hpp"
#include "hal/candump/candump_log.hpp"
#include "hal/clock.hpp"

namespace scopekin::hal {

class RecordingCanBus final : public CanBus {
public:
    RecordingCanBus(CanBus& bus, const MonotonicClock& clock) : bus_(&bus), clock_(&clock) {}
    ~RecordingCanBus();
    RecordingCanBus(const RecordingCanBus&) = delete;
    RecordingCanBus& operator=(const RecordingCanBus&) = delete;

    /// Starts recording into `path` (created or truncated) under the interface name `interface`.
    bool open(const std::string& path, const std::string& interface, std::string& error);
    /// Flushes and closes the file; returns false if anything could not be written.
    bool close();

    CanStatus send(const CanFrame& frame, std::uint32_t timeout_us) override;
    /// Sent frames from now on carry this monotonic time (the period's release time).
    void set_send_time_us(std::uint64_t monotonic_us) {
        send_time_us_ = monotonic_us;
        has_send_time_ = true;
    }
    CanStatus receive(ReceivedCanFrame& received, std::uint32_t timeout_us) override;
    [[nodiscard]] CanCounters counters() const override { return bus_->counters(); }
    /// Passed on: the record holds what passed the filter (what the box received).
    CanStatus set_receive_filter(std::span<const CanIdFilter> filters) override {
        return bus_->set_receive_filter(filters);
    }

    [[nodiscard]] std::uint64_t lines_written() const { return lines_; }
    [[nodiscard]] std::uint64_t write_errors() const { return write_errors_; }

private:
    void record(const CanFrame& frame, std::uint64_t monotonic_us);

    CanBus* bus_;
    const MonotonicClock* clock_;
    std::FILE* file_{nullptr};
    CandumpRecord record_{};
    std::int64_t realtime_offset_us_{0};
    std::uint64_t last_flush_us_{0};
    std::uint64_t lines_{0};
    std::uint64_t write_errors_{0};
    std::uint64_t send_time_us_{0};
    bool has_send_time_{false};
};

}  // namespace scopekin::hal
