// linux_clock.cpp — see linux_clock.hpp.
#include "hal/linux/linux_clock.hpp"

#include <ctime>

namespace scopekin::hal {

namespace {
std::uint64_t read_us(clockid_t clock) {
    timespec now{};
    clock_gettime(clock, &now);
    return static_cast<std::uint64_t>(now.tv_sec) * 1000000U +
           static_cast<std::uint64_t>(now.tv_nsec) / 1000U;
}
}  // namespace

std::uint64_t LinuxMonotonicClock::now_us() const {
    return read_us(CLOCK_MONOTONIC);
}

void LinuxMonotonicClock::wait_until_us(std::uint64_t deadline_us) {
    timespec deadline{};
    deadline.tv_sec = static_cast<time_t>(deadline_us / 1000000U);
    deadline.tv_nsec = static_cast<long>((deadline_us % 1000000U) * 1000U);
    // EINTR: return early (see the header); any other error: the deadline is in the past.
    (void)clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr);
}

std::uint64_t realtime_now_us() {
    return read_us(CLOCK_REALTIME);
}

}  // namespace scopekin::hal
