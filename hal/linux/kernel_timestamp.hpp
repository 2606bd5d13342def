// kernel_timestamp.hpp — a kernel receive time stamp taken on CLOCK_REALTIME (what SO_TIMESTAMP
// gives a socket) moved onto CLOCK_MONOTONIC, the clock the box runs on, without being fooled by
// a wall-clock step (settimeofday, `date -s`, an NTP step) while frames wait in the socket.
//
// The plain conversion subtracts the offset between the two clocks read when the frame is taken
// from the socket: monotonic = stamp - (realtime_now - monotonic_now).  That is exact unless the
// wall clock was stepped between the kernel stamping the frame and the read: then every frame
// stamped before the step is off by the step (an hour's forward step made them an hour old,
// clamped to the boot, and the box's candump record went backwards by seconds).  Frames leave a
// CAN_RAW socket in the order they were stamped, so a correct result is never older than the
// previous frame's and never later than now; a result outside [previous, now] means the offset
// changed while the frame waited, and the offset that served the previous frame (the one before
// the step) is used instead.  If neither fits, the result is clamped into [previous, now].  Old
// frames stay old (a backlog after a stall keeps its true ages), only their order is enforced.
// Header only, integer arithmetic, no system calls: the caller reads the clocks.
#pragma once

#include <cstdint>

namespace scopekin::hal {

class RealtimeStampConverter {
public:
    /// `stamp_realtime_us`: the kernel's stamp (µs since 1970; pass `realtime_now_us` when the
    /// frame came without one); `realtime_now_us` and `monotonic_now_us`: the two clocks read
    /// just now.  Returns the stamp on CLOCK_MONOTONIC (µs), never before the previous result and
    /// never after `monotonic_now_us`.
    [[nodiscard]] std::uint64_t to_monotonic(std::uint64_t stamp_realtime_us,
                                             std::uint64_t realtime_now_us,
                                             std::uint64_t monotonic_now_us) noexcept {
        const std::int64_t offset_now = static_cast<std::int64_t>(realtime_now_us) -
                                        static_cast<std::int64_t>(monotonic_now_us);
        const std::int64_t stamp = static_cast<std::int64_t>(stamp_realtime_us);
        const auto low = static_cast<std::int64_t>(last_us_);
        const auto high = static_cast<std::int64_t>(monotonic_now_us);
        std::int64_t result = stamp - offset_now;
        std::int64_t used_offset = offset_now;
        if ((result < low || result > high) && has_offset_) {
            const std::int64_t before_step = stamp - last_offset_;
            if (before_step >= low && before_step <= high) {
                result = before_step;
                used_offset = last_offset_;
            }
        }
        if (result < low) result = low;
        if (result > high) result = high;
        last_offset_ = used_offset;
        has_offset_ = true;
        last_us_ = static_cast<std::uint64_t>(result);
        return last_us_;
    }

    /// Forgets the history (a new socket).
    void reset() noexcept { *this = RealtimeStampConverter{}; }

private:
    std::int64_t last_offset_{0};  ///< realtime - monotonic that served the previous frame
    bool has_offset_{false};
    std::uint64_t last_us_{0};  ///< the previous result
};

}  // namespace scopekin::hal
