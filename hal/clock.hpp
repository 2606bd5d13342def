// clock.hpp — monotonic time and the periodic wait of the cyclic executive.
//
// MonotonicClock backends: hal/linux (CLOCK_MONOTONIC + clock_nanosleep), hal/loopback
// (simulated time owned by the simulator), hal/bare_metal (SysTick).  Microseconds throughout:
// 2^64 µs is 584,000 years, so nothing wraps.
#pragma once

#include <cstdint>

namespace scopekin::hal {

class MonotonicClock {
public:
    [[nodiscard]] virtual std::uint64_t now_us() const = 0;
    /// Returns at (or, on a loaded system, after) `deadline_us`; at once if it has passed.
    virtual void wait_until_us(std::uint64_t deadline_us) = 0;

protected:
    MonotonicClock() = default;
    ~MonotonicClock() = default;
    MonotonicClock(const MonotonicClock&) = default;
    MonotonicClock& operator=(const MonotonicClock&) = default;
};

/// Fixed-rate release of the cyclic executive: deadlines at start + k * period.  A period that
/// overran (the work took longer than the period) is counted and the schedule skips ahead to the
/// next deadline in the future, so the executive never runs a burst of catch-up periods.
class PeriodicTimer {
public:
    PeriodicTimer(MonotonicClock& clock, std::uint32_t period_us)
        : clock_(&clock),
          period_us_(period_us == 0U ? 1U : period_us),
          next_deadline_us_(clock.now_us() + period_us_) {}

    /// Waits for the next release; returns the release time (the deadline, in µs).
    std::uint64_t wait_next() {
        const std::uint64_t now = clock_->now_us();
        if (now > next_deadline_us_) {
            const std::uint64_t missed = (now - next_deadline_us_) / period_us_ + 1U;
            overruns_ += static_cast<std::uint32_t>(missed);
            next_deadline_us_ += missed * period_us_;
        }
        clock_->wait_until_us(next_deadline_us_);
        const std::uint64_t release = next_deadline_us_;
        next_deadline_us_ += period_us_;
        return release;
    }

    [[nodiscard]] std::uint32_t period_us() const { return period_us_; }
    /// Periods skipped because the work overran its period.
    [[nodiscard]] std::uint32_t overruns() const { return overruns_; }

private:
    MonotonicClock* clock_;
    std::uint32_t period_us_;
    std::uint64_t next_deadline_us_;
    std::uint32_t overruns_{0};
};

}  // namespace scopekin::hal
