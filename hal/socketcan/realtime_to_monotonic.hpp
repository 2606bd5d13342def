// realtime_to_monotonic.hpp — the kernel's receive time stamps (SO_TIMESTAMP: CLOCK_REALTIME) on
// the executive's clock (CLOCK_MONOTONIC), robust to a step of the wall clock.
//
// A frame's monotonic receive time is its realtime stamp minus the offset realtime - monotonic.
// The offset is read at every receive (both clocks, µs).  When the wall clock steps (date -s,
// settimeofday, an NTP step) between a frame's stamp and its receive, the frame was stamped with
// the old offset: with the new one it would look older by the step (forward) or be in the future
// (backward).  So the offset in force before the last step is kept for kPreviousOffsetKeptUs
// (longer than the socket buffer holds frames: ~1500 frames, 0.7 s of both sensors at 1 kHz)
// and each stamp is mapped with whichever offset gives the latest time that is not in the future
// — the right one for a frame younger than the step's size; an older frame (a backlog) may come
// out newer by at most the step.  A stamp that maps into the future with both offsets is taken
// as received now (age 0).  Slow changes of the offset (NTP slewing, at most 0.5 µs per ms) are
// followed at every receive; a change above kStepUs between two receives counts as a step.
// The mapped times never go back: the socket hands frames out in the order they arrived, so a
// frame read after another is given at least that one's time (the two clock readings behind each
// offset differ by a µs or so from one receive to the next, which would otherwise reorder two
// frames stamped in the same µs — and `scopekin replay` refuses a record whose time goes back).
//
// Plain integer arithmetic, no system calls: the SocketCAN backend feeds it, the tests drive it.
#pragma once

#include <cstdint>

namespace scopekin::hal {

class RealtimeToMonotonic {
public:
    /// An offset change larger than this between two receives is a step of the wall clock.
    static constexpr std::int64_t kStepUs = 1000;
    /// How long after a step the offset before it is still tried.
    static constexpr std::uint64_t kPreviousOffsetKeptUs = 1'000'000;

    /// The monotonic time of a frame stamped `stamp_realtime_us`, received when the clocks read
    /// `realtime_now_us` and `monotonic_now_us`.  Never after `monotonic_now_us`.
    [[nodiscard]] constexpr std::uint64_t map(std::uint64_t stamp_realtime_us,
                                              std::uint64_t realtime_now_us,
                                              std::uint64_t monotonic_now_us) {
        const std::int64_t offset_now = static_cast<std::int64_t>(realtime_now_us) -
                                        static_cast<std::int64_t>(monotonic_now_us);
        if (has_offset_) {
            const std::int64_t change = offset_now - offset_us_;
            if (change > kStepUs || change < -kStepUs) {
                previous_offset_us_ = offset_us_;
                step_at_us_ = monotonic_now_us;
                has_previous_ = true;
            }
        }
        offset_us_ = offset_now;
        has_offset_ = true;
        if (has_previous_ && monotonic_now_us - step_at_us_ > kPreviousOffsetKeptUs) {
            has_previous_ = false;
        }
        const std::int64_t now = static_cast<std::int64_t>(monotonic_now_us);
        const std::int64_t stamp = static_cast<std::int64_t>(stamp_realtime_us);
        std::int64_t best = -1;
        const std::int64_t current = stamp - offset_us_;
        if (current >= 0 && current <= now) {
            best = current;
        }
        if (has_previous_) {
            const std::int64_t before_step = stamp - previous_offset_us_;
            if (before_step >= 0 && before_step <= now && before_step > best) {
                best = before_step;
            }
        }
        std::uint64_t mapped = best < 0 ? monotonic_now_us : static_cast<std::uint64_t>(best);
        if (mapped < last_us_ && last_us_ <= monotonic_now_us) {
            mapped = last_us_;
        }
        last_us_ = mapped;
        return mapped;
    }

private:
    std::int64_t offset_us_{0};
    std::int64_t previous_offset_us_{0};
    std::uint64_t step_at_us_{0};
    std::uint64_t last_us_{0};  ///< the last time handed out
    bool has_offset_{false};
    bool has_previous_{false};
};

}  // namespace scopekin::hal
