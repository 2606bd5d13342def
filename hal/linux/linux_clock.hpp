// linux_clock.hpp — hal::MonotonicClock on CLOCK_MONOTONIC; waits with clock_nanosleep on an
// absolute deadline (no drift from relative sleeps).  A signal interrupts the wait: it returns
// early so the caller's loop can look at its stop flag (the caller's PeriodicTimer keeps the
// schedule).
#pragma once

#include <cstdint>

#include "hal/clock.hpp"

namespace scopekin::hal {

class LinuxMonotonicClock final : public MonotonicClock {
public:
    [[nodiscard]] std::uint64_t now_us() const override;
    void wait_until_us(std::uint64_t deadline_us) override;
};

/// CLOCK_REALTIME in µs since 1970 (candump log timestamps).
[[nodiscard]] std::uint64_t realtime_now_us();

}  // namespace scopekin::hal
