// systick_clock.hpp — hal::MonotonicClock on the Cortex-M SysTick timer, polled (no interrupt).
//
// SysTick counts down from 0xFFFFFF at the CPU clock (25 MHz on QEMU's mps2-an386: 40 ns per
// tick, hw/arm/mps2.c SYSCLK_FRQ).  Each now_us() adds the ticks elapsed since the previous
// read (modulo 2^24) to a 64-bit total, so it must be called at least once per 2^24 ticks
// (0.67 s at 25 MHz) — the executive reads it every period.  Under QEMU `-icount shift=0` one
// instruction is 1 ns, so this clock is deterministic in tests.
// wait_until_us busy-polls (a real board would sleep in WFI until a timer interrupt).
#pragma once

#include <cstdint>

#include "hal/clock.hpp"

namespace scopekin::hal {

class SysTickClock final : public MonotonicClock {
public:
    explicit SysTickClock(std::uint32_t cpu_clock_hz = 25'000'000U);

    [[nodiscard]] std::uint64_t now_us() const override;
    void wait_until_us(std::uint64_t deadline_us) override;

private:
    std::uint32_t ticks_per_us_;
    mutable std::uint32_t last_count_{0};
    mutable std::uint64_t total_ticks_{0};
};

}  // namespace scopekin::hal
