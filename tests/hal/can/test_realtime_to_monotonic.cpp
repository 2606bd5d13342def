// The SocketCAN backend's mapping of the kernel's realtime receive stamps onto the monotonic
// clock (hal/socketcan/realtime_to_monotonic.hpp): exact without a wall-clock step; a frame
// stamped before a step, forward or backward, keeps its true receive time; after the step new
// frames map exactly; the old offset is forgotten 1 s after the step; the mapped times never go
// back, whatever the jitter of the two clock readings.  Times in µs; the wall clock runs at
// 1.7e9 s, the monotonic one at 1000 s.
#include <cstdint>

#include "hal/socketcan/realtime_to_monotonic.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::hal::RealtimeToMonotonic;

constexpr std::uint64_t kMonotonic0 = 1'000'000'000ULL;         // 1000 s
constexpr std::uint64_t kRealtime0 = 1'700'000'000'000'000ULL;  // 1.7e9 s
constexpr std::uint64_t kOffset = kRealtime0 - kMonotonic0;     // realtime - monotonic
constexpr std::uint64_t kHourUs = 3'600'000'000ULL;

}  // namespace

SCOPEKIN_TEST(RealtimeToMonotonic, WithoutAStepTheAgeIsKept) {
    RealtimeToMonotonic clock{};
    // Received 300 µs after its stamp: 300 µs old on the monotonic clock too.
    SCOPEKIN_EXPECT_EQ(clock.map(kRealtime0, kRealtime0 + 300U, kMonotonic0 + 300U), kMonotonic0);
    // A stamp "after" the receive (clock reads differ by µs): age 0.
    SCOPEKIN_EXPECT_EQ(clock.map(kRealtime0 + 1000U, kRealtime0 + 900U, kMonotonic0 + 900U),
                       kMonotonic0 + 900U);
    // NTP slewing: the offset drifts 0.5 µs per ms, followed.
    SCOPEKIN_EXPECT_EQ(clock.map(kRealtime0 + 5002U, kRealtime0 + 5202U, kMonotonic0 + 5200U),
                       kMonotonic0 + 5000U);
}

SCOPEKIN_TEST(RealtimeToMonotonic, AForwardStepDoesNotAgeFramesStampedBeforeIt) {
    RealtimeToMonotonic clock{};
    (void)clock.map(kRealtime0, kRealtime0, kMonotonic0);
    // A frame stamped at monotonic +4 ms; the wall clock jumps 1 h forward at +4.5 ms; the frame
    // is read at +5 ms.  With the new offset alone it would be 1 h old.
    const std::uint64_t stamp = kMonotonic0 + 4000U + kOffset;
    SCOPEKIN_EXPECT_EQ(clock.map(stamp, kRealtime0 + 5000U + kHourUs, kMonotonic0 + 5000U),
                       kMonotonic0 + 4000U);
    // A frame stamped after the step maps exactly.
    const std::uint64_t after = kMonotonic0 + 5500U + kOffset + kHourUs;
    SCOPEKIN_EXPECT_EQ(clock.map(after, kRealtime0 + 6000U + kHourUs, kMonotonic0 + 6000U),
                       kMonotonic0 + 5500U);
}

SCOPEKIN_TEST(RealtimeToMonotonic, ABackwardStepDoesNotPutFramesInTheFuture) {
    RealtimeToMonotonic clock{};
    (void)clock.map(kRealtime0, kRealtime0, kMonotonic0);
    // Stamped at +4 ms, the wall clock set back 1 h at +4.5 ms, read at +5 ms.
    const std::uint64_t stamp = kMonotonic0 + 4000U + kOffset;
    SCOPEKIN_EXPECT_EQ(clock.map(stamp, kRealtime0 + 5000U - kHourUs, kMonotonic0 + 5000U),
                       kMonotonic0 + 4000U);
    const std::uint64_t after = kMonotonic0 + 5500U + kOffset - kHourUs;
    SCOPEKIN_EXPECT_EQ(clock.map(after, kRealtime0 + 6000U - kHourUs, kMonotonic0 + 6000U),
                       kMonotonic0 + 5500U);
}

SCOPEKIN_TEST(RealtimeToMonotonic, TheOffsetBeforeAStepIsForgottenAfterOneSecond) {
    RealtimeToMonotonic clock{};
    (void)clock.map(kRealtime0, kRealtime0, kMonotonic0);
    // A 2 ms forward step at +1 ms.
    (void)clock.map(kRealtime0 + 1000U + 2000U, kRealtime0 + 1000U + 2000U, kMonotonic0 + 1000U);
    // 0.5 s later a frame 3 ms old (a backlog): the old offset would make it 1 ms old, and is
    // still tried, so the frame may come out newer by at most the step.
    const std::uint64_t half = kMonotonic0 + 500'000U;
    const std::uint64_t old_frame = half - 3000U + kOffset + 2000U;
    const std::uint64_t mapped = clock.map(old_frame, half + kOffset + 2000U, half);
    SCOPEKIN_EXPECT_TRUE(mapped >= half - 3000U && mapped <= half - 3000U + 2000U);
    // 1.1 s after the step: exact again.
    const std::uint64_t later = kMonotonic0 + 1'101'000U;
    SCOPEKIN_EXPECT_EQ(clock.map(later - 3000U + kOffset + 2000U, later + kOffset + 2000U, later),
                       later - 3000U);
}

// Two frames stamped in the same µs, read one after the other; between the two receives the
// realtime reading came out 2 µs late (the readings are not one instant): the second frame must
// not be placed before the first.
SCOPEKIN_TEST(RealtimeToMonotonic, TimesNeverGoBack) {
    RealtimeToMonotonic clock{};
    const std::uint64_t first = clock.map(kRealtime0, kRealtime0 + 100U, kMonotonic0 + 100U);
    SCOPEKIN_EXPECT_EQ(first, kMonotonic0);
    const std::uint64_t second = clock.map(kRealtime0, kRealtime0 + 112U, kMonotonic0 + 110U);
    SCOPEKIN_EXPECT_EQ(second, kMonotonic0);  // not 2 µs before the first
    const std::uint64_t third = clock.map(kRealtime0 + 10U, kRealtime0 + 110U, kMonotonic0 + 110U);
    SCOPEKIN_EXPECT_EQ(third, kMonotonic0 + 10U);
}

// A queue of frames waits in the socket across a step, some stamped before it and some after,
// and the box has run longer than the step (so the new offset alone gives a plausible time, an
// hour old): every frame keeps its true receive time, forward and backward.
SCOPEKIN_TEST(RealtimeToMonotonic, AQueueAcrossAStepKeepsItsTimesAfterHoursOfRunning) {
    constexpr std::uint64_t kUp = 2U * kHourUs;  // the box has run two hours
    for (int direction = 0; direction < 2; ++direction) {
        const bool forward = direction == 0;
        RealtimeToMonotonic clock{};
        std::uint64_t offset = kOffset;
        std::uint64_t t = kUp;
        for (; t < kUp + 10'000U; t += 500U) {
            SCOPEKIN_EXPECT_EQ(clock.map(t + offset, t + 1000U + offset, t + 1000U), t);
        }
        std::uint64_t arrived[12]{};
        std::uint64_t stamps[12]{};
        for (int k = 0; k < 12; ++k, t += 500U) {
            if (k == 8) {
                offset = forward ? offset + kHourUs : offset - kHourUs;  // date -s +/-1 h
            }
            arrived[k] = t;
            stamps[k] = t + offset;
        }
        for (int k = 0; k < 12; ++k) {
            SCOPEKIN_EXPECT_EQ(clock.map(stamps[k], t + offset, t), arrived[k]);
        }
        // A backlog after a stall of half a second keeps its ages too.
        const std::uint64_t stalled = t + 500'000U;
        for (std::uint64_t a = t; a < t + 5000U; a += 1000U) {
            SCOPEKIN_EXPECT_EQ(clock.map(a + offset, stalled + offset, stalled), a);
        }
    }
}
