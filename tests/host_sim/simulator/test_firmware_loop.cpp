// The unmodified firmware on the loopback HAL (host_sim/simulator/firmware_loop.hpp): which
// periods run for which rows. Expected counts follow from the 5 ms period alone.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "host_sim/recording/recording_row.hpp"
#include "host_sim/simulator/firmware_loop.hpp"

namespace scopekin::host_sim {
namespace {

recording::RecordingRow handle_row(std::int64_t time_us) {
    recording::RecordingRow row;
    row.time_us = time_us;
    row.handle = recording::ForceTorqueCells{1.0, 0.0};
    row.insertion_roll = recording::InsertionRollCells{100.0, 0.0};
    return row;
}

TEST(FirmwareLoop, PeriodsRunAtEveryFiveMillisecondsUpToTheLastRow) {
    std::vector<std::uint64_t> times;
    FirmwareLoop loop([&](const BoxPeriod& p) { times.push_back(p.time_us); });
    for (std::int64_t ms = 1; ms <= 20; ++ms)
        loop.deliver(handle_row(ms * 1000));
    loop.finish(20000);
    EXPECT_EQ(times, (std::vector<std::uint64_t>{5000, 10000, 15000, 20000}));
}

TEST(FirmwareLoop, TheBoxStartsWithTheFirstRow) {
    // A recording that starts at 500 s (a logger's clock): the first period is the first release
    // at or after the first row, not 100,000 empty periods from 0 s.
    std::vector<std::uint64_t> times;
    FirmwareLoop loop([&](const BoxPeriod& p) { times.push_back(p.time_us); });
    for (std::int64_t ms = 0; ms <= 20; ++ms)
        loop.deliver(handle_row(500'000'001 + ms * 1000));
    loop.finish(500'020'001);
    EXPECT_EQ(times,
              (std::vector<std::uint64_t>{500'005'000, 500'010'000, 500'015'000, 500'020'000}));
    // A first row exactly at a release: that period runs after the row is delivered.
    times.clear();
    FirmwareLoop exact([&](const BoxPeriod& p) { times.push_back(p.time_us); });
    exact.deliver(handle_row(1'000'000));
    exact.finish(1'000'000);
    EXPECT_EQ(times, (std::vector<std::uint64_t>{1'000'000}));
}

}  // namespace
}  // namespace scopekin::host_sim
