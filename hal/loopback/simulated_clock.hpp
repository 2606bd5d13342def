// simulated_clock.hpp — a MonotonicClock whose time only moves when the simulator says so.
//
// The host simulator owns time: it advances the clock (advance_to / advance_by) and waiting
// (the executive's periodic wait) jumps time to the deadline at once.  Deterministic: no
// reading of the machine's clock anywhere.
#pragma once

#include <cstdint>

#include "hal/clock.hpp"

namespace scopekin::hal {

class SimulatedClock final : public MonotonicClock {
public:
    explicit SimulatedClock(std::uint64_t start_us = 0) : now_us_(start_us) {}

    [[nodiscard]] std::uint64_t now_us() const override { return now_us_; }
    /// Waiting in simulated time: jump to the deadline (never backwards).
    void wait_until_us(std::uint64_t deadline_us) override { advance_to(deadline_us); }

    void advance_to(std::uint64_t time_us) {
        if (time_us > now_us_) {
            now_us_ = time_us;
        }
    }
    void advance_by(std::uint64_t duration_us) { now_us_ += duration_us; }

private:
    std::uint64_t now_us_;
};

}  // namespace scopekin::hal
