// systick_clock.cpp — see systick_clock.hpp.
#include "hal/bare_metal/systick_clock.hpp"

namespace scopekin::hal {

namespace {
constexpr std::uintptr_t kSystCsr = 0xE000E010U;  // control and status
constexpr std::uintptr_t kSystRvr = 0xE000E014U;  // reload value
constexpr std::uintptr_t kSystCvr = 0xE000E018U;  // current value
constexpr std::uint32_t kCsrEnable = 1U << 0U;
constexpr std::uint32_t kCsrClkSourceCpu = 1U << 2U;
constexpr std::uint32_t kCountMask = 0x00FFFFFFU;

volatile std::uint32_t& reg(std::uintptr_t address) {
    return *reinterpret_cast<volatile std::uint32_t*>(address);
}
}  // namespace

SysTickClock::SysTickClock(std::uint32_t cpu_clock_hz)
    : ticks_per_us_(cpu_clock_hz / 1'000'000U == 0U ? 1U : cpu_clock_hz / 1'000'000U) {
    reg(kSystCsr) = 0U;
    reg(kSystRvr) = kCountMask;
    reg(kSystCvr) = 0U;                             // reload on the next edge
    reg(kSystCsr) = kCsrClkSourceCpu | kCsrEnable;  // no interrupt: polled
    last_count_ = kCountMask;
}

std::uint64_t SysTickClock::now_us() const {
    const std::uint32_t count = reg(kSystCvr) & kCountMask;
    total_ticks_ += (last_count_ - count) & kCountMask;  // counts down; wraps at 2^24
    last_count_ = count;
    return total_ticks_ / ticks_per_us_;
}

void SysTickClock::wait_until_us(std::uint64_t deadline_us) {
    // Bounded by the deadline: time always advances while polling.
    while (now_us() < deadline_us) {
    }
}

}  // namespace scopekin::hal
