// RealtimeStampConverter (hal/linux/kernel_timestamp.hpp): kernel receive stamps (CLOCK_REALTIME)
// moved onto CLOCK_MONOTONIC by the SocketCAN backend.  The clocks here are numbers: a wall clock
// that is the monotonic one plus an offset, stepped by the tests while frames wait in the
// "socket" (stamped with the old offset, read after the step).  What must hold: every frame gets
// the monotonic time it really arrived at, to the µs, whether the wall clock was stepped forward
// or back meanwhile; results never go backwards and never lie in the future; a backlog keeps its
// true (old) ages.
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "hal/linux/kernel_timestamp.hpp"

namespace {

using scopekin::hal::RealtimeStampConverter;

constexpr std::uint64_t kEpochUs = 1'700'000'000'000'000ULL;  // wall clock at monotonic 0
constexpr std::int64_t kHourUs = 3'600'000'000LL;

/// A frame as the kernel queued it: when it really arrived (monotonic) and its stamp.
struct QueuedFrame {
    std::uint64_t arrived_monotonic_us;
    std::uint64_t stamp_realtime_us;
};

class TwoClocks {
public:
    [[nodiscard]] std::uint64_t realtime(std::uint64_t monotonic_us) const {
        return static_cast<std::uint64_t>(static_cast<std::int64_t>(kEpochUs + monotonic_us) +
                                          step_us_);
    }
    void step(std::int64_t by_us) { step_us_ += by_us; }
    /// The kernel stamps a frame arriving at `monotonic_us` with the wall clock of that moment.
    [[nodiscard]] QueuedFrame arrive(std::uint64_t monotonic_us) const {
        return {monotonic_us, realtime(monotonic_us)};
    }
    /// The box reads `frame` at `monotonic_now_us`.
    std::uint64_t read(RealtimeStampConverter& converter, const QueuedFrame& frame,
                       std::uint64_t monotonic_now_us) const {
        return converter.to_monotonic(frame.stamp_realtime_us, realtime(monotonic_now_us),
                                      monotonic_now_us);
    }

private:
    std::int64_t step_us_{0};
};

}  // namespace

TEST(RealtimeStampConverter, NoStepGivesTheArrivalTimeExactly) {
    TwoClocks clocks;
    RealtimeStampConverter converter;
    for (std::uint64_t t = 1'000'000; t < 1'050'000; t += 500) {
        const QueuedFrame frame = clocks.arrive(t);
        EXPECT_EQ(clocks.read(converter, frame, t + 3'000), t);  // read 3 ms later
    }
}

// The defect this guards: frames stamped before a forward step and read after it came out an
// hour old (clamped to 0), and the record of the box went backwards.
TEST(RealtimeStampConverter, ForwardStepWhileFramesWaitKeepsTheirArrivalTimes) {
    TwoClocks clocks;
    RealtimeStampConverter converter;
    std::uint64_t t = 5'000'000;
    for (; t < 5'010'000; t += 500) {
        EXPECT_EQ(clocks.read(converter, clocks.arrive(t), t + 1'000), t);
    }
    std::vector<QueuedFrame> queued;
    for (int k = 0; k < 8; ++k, t += 500) {
        queued.push_back(clocks.arrive(t));  // waiting in the socket
    }
    clocks.step(kHourUs);  // date -s +1 h
    for (int k = 0; k < 4; ++k, t += 500) {
        queued.push_back(clocks.arrive(t));  // stamped after the step
    }
    for (const QueuedFrame& frame : queued) {
        EXPECT_EQ(clocks.read(converter, frame, t), frame.arrived_monotonic_us);
    }
    for (int k = 0; k < 10; ++k, t += 500) {
        EXPECT_EQ(clocks.read(converter, clocks.arrive(t), t + 200), t);
    }
}

TEST(RealtimeStampConverter, BackwardStepWhileFramesWaitKeepsTheirArrivalTimes) {
    TwoClocks clocks;
    RealtimeStampConverter converter;
    std::uint64_t t = 7'000'000;
    EXPECT_EQ(clocks.read(converter, clocks.arrive(t), t), t);
    std::vector<QueuedFrame> queued;
    for (int k = 0; k < 6; ++k) {
        t += 500;
        queued.push_back(clocks.arrive(t));
    }
    clocks.step(-2 * kHourUs);  // date -s -2 h: the old stamps now lie in the future
    for (int k = 0; k < 6; ++k) {
        t += 500;
        queued.push_back(clocks.arrive(t));
    }
    for (const QueuedFrame& frame : queued) {
        EXPECT_EQ(clocks.read(converter, frame, t + 100), frame.arrived_monotonic_us);
    }
}

TEST(RealtimeStampConverter, BacklogAfterAStallKeepsItsTrueAges) {
    TwoClocks clocks;
    RealtimeStampConverter converter;
    std::vector<QueuedFrame> backlog;
    for (std::uint64_t t = 2'000'000; t < 2'500'000; t += 1'000) {
        backlog.push_back(clocks.arrive(t));
    }
    const std::uint64_t read_at = 3'000'000;  // the box stalled for a second
    for (const QueuedFrame& frame : backlog) {
        EXPECT_EQ(clocks.read(converter, frame, read_at), frame.arrived_monotonic_us);
    }
}

TEST(RealtimeStampConverter, NeverBackwardsNeverInTheFuture) {
    TwoClocks clocks;
    RealtimeStampConverter converter;
    const std::uint64_t first = clocks.read(converter, clocks.arrive(1'000'000), 1'000'100);
    EXPECT_EQ(first, 1'000'000U);
    // A stamp earlier than the previous frame's (clock jitter, a broken driver) is held at it.
    const QueuedFrame earlier{999'990, clocks.realtime(999'990)};
    EXPECT_EQ(clocks.read(converter, earlier, 1'000'200), first);
    // A stamp in the future of now is held at now.
    const QueuedFrame future{1'000'900, clocks.realtime(1'000'900)};
    EXPECT_EQ(clocks.read(converter, future, 1'000'300), 1'000'300U);
    // No stamp at all (the caller passes the wall clock of now): now.
    EXPECT_EQ(
        converter.to_monotonic(clocks.realtime(1'000'400), clocks.realtime(1'000'400), 1'000'400),
        1'000'400U);
    converter.reset();
    EXPECT_EQ(clocks.read(converter, clocks.arrive(10), 20), 10U);
}
