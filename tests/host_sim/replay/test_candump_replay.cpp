// What `scopekin replay` does with a candump log (host_sim/replay/candump_replay.hpp):
//   * the reader refuses any time stamp earlier than the line before it (a reversed, shuffled
//     or spliced log), naming both lines; equal time stamps are fine;
//   * the reader refuses a gap between two lines longer than the bound (--max-gap-s, default
//     60 s), naming the line, so a sensor log's replay (a period every 5 ms) is always finite;
//   * the replay gives the box only the frames that pass the box's receive filter, as the
//     kernel does for scopekin-box: a flood of foreign frames changes no output.
// The handle frames are made with the DBC's codecs (firmware/protocol/can), the expected values
// from the log's own construction (a 50 mm/s advance, 2 N).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "hal/candump/candump_log.hpp"
#include "host_sim/replay/candump_replay.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace {

namespace fs = std::filesystem;
using scopekin::fixed_point::Q16_16;
namespace hal = scopekin::hal;
namespace host_sim = scopekin::host_sim;
namespace protocol = scopekin::protocol;

constexpr std::uint64_t kStartUs = 1'000'000'000'000ULL;  // 1e6 s, like the VM test's logs

/// A log file in the test's own folder (removed first).
std::string write_log(const std::string& name, const std::vector<std::string>& lines) {
    const fs::path dir = fs::temp_directory_path() / "scopekin_test_candump_replay";
    fs::create_directories(dir);
    const fs::path path = dir / name;
    std::ofstream out(path, std::ios::trunc);
    for (const std::string& line : lines)
        out << line << "\n";
    return path.string();
}

/// One candump line of `frame` at `time_us`.
std::string line_of(std::uint64_t time_us, const hal::CanFrame& frame) {
    hal::CandumpRecord record{};
    record.timestamp_us = time_us;
    record.frame = frame;
    hal::set_candump_interface(record, "can0");
    std::array<char, hal::kCandumpLineCapacity> text{};
    const std::size_t length = hal::format_candump_line(record, text);
    EXPECT_GT(length, 1U);
    return std::string(text.data(), length - 1U);  // without the '\n'
}

hal::CanFrame force_frame(std::uint32_t k) {
    protocol::HandleForceTorque force{};
    force.force_N = Q16_16::from_int(2);
    force.counter = static_cast<std::uint8_t>(k % 16U);
    return protocol::encode(force);
}

hal::CanFrame encoder_frame(std::uint32_t k) {
    protocol::InsertionRoll encoder{};
    // 100 mm + 0.05 mm per ms (50 mm/s), in the encoder's 0.01 mm steps.
    encoder.insertion_mm = Q16_16::from_ratio(static_cast<std::int32_t>(10000 + 5 * k), 100);
    encoder.counter = static_cast<std::uint8_t>(k % 16U);
    return protocol::encode(encoder);
}

/// Both handle sensors at 1 kHz for `ms` milliseconds, and `foreign_per_ms` frames of other
/// identifiers (0x300..0x3FF, 8 bytes) each millisecond beside them.
host_sim::CandumpLog sensor_log(std::uint32_t ms, std::uint32_t foreign_per_ms) {
    host_sim::CandumpLog log;
    auto add = [&log](std::uint64_t time_us, const hal::CanFrame& frame) {
        hal::CandumpRecord record{};
        record.timestamp_us = time_us;
        record.frame = frame;
        hal::set_candump_interface(record, "can0");
        log.records.push_back(record);
        log.lines.push_back(log.records.size());
    };
    for (std::uint32_t k = 0; k < ms; ++k) {
        const std::uint64_t t = kStartUs + std::uint64_t{k} * 1000U;
        add(t, encoder_frame(k));
        add(t, force_frame(k));
        for (std::uint32_t j = 0; j < foreign_per_ms; ++j) {
            hal::CanFrame foreign{};
            foreign.id = 0x300U + j % 0x100U;
            foreign.length = 8;
            foreign.data = {0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77};
            add(t, foreign);
        }
    }
    return log;
}

/// The text of a refusal, and its line (0 if none was thrown).
struct Refusal {
    std::size_t line = 0;
    std::string message;
};

Refusal refusal_of(const std::string& path,
                   const host_sim::CandumpReadOptions& options = host_sim::CandumpReadOptions{}) {
    try {
        (void)host_sim::read_candump_log(path, options);
    } catch (const host_sim::CandumpLineError& e) {
        return {e.line(), e.what()};
    }
    return {};
}

std::vector<std::string> sensor_lines(std::uint32_t ms) {
    std::vector<std::string> lines;
    for (std::uint32_t k = 0; k < ms; ++k) {
        lines.push_back(line_of(kStartUs + std::uint64_t{k} * 1000U, encoder_frame(k)));
        lines.push_back(line_of(kStartUs + std::uint64_t{k} * 1000U, force_frame(k)));
    }
    return lines;
}

}  // namespace

TEST(CandumpReplayReader, ATimeStampBeforeThePreviousLineIsRefusedNamingBothLines) {
    std::vector<std::string> lines = sensor_lines(10);  // lines 1..20, 1 ms apart in pairs
    std::swap(lines[10], lines[12]);  // line 11 is now the 6 ms frame, line 12 one of 5 ms
    const std::string path = write_log("swapped.log", lines);
    const Refusal r = refusal_of(path);
    EXPECT_EQ(r.line, 12U) << r.message;  // 1 ms back: the old reader let up to 1 s pass
    EXPECT_NE(r.message.find("line 12"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("line 11"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("0.001 s before line 11"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find(path), std::string::npos) << r.message;
}

TEST(CandumpReplayReader, AReversedLogIsRefusedAtItsFirstStepBack) {
    std::vector<std::string> lines = sensor_lines(4000);  // 4 s, steps of 1 ms: none back by 1 s
    std::reverse(lines.begin(), lines.end());
    const Refusal r = refusal_of(write_log("reversed.log", lines));
    EXPECT_EQ(r.line, 3U) << r.message;  // lines 1 and 2 share the last millisecond
}

TEST(CandumpReplayReader, AShuffledLogIsRefused) {
    std::vector<std::string> lines = sensor_lines(100);
    std::uint32_t seed = 7;
    for (std::size_t i = lines.size() - 1; i > 0; --i) {  // Fisher-Yates, a fixed LCG
        seed = seed * 1664525U + 1013904223U;
        std::swap(lines[i], lines[(seed >> 8U) % (i + 1U)]);
    }
    const Refusal r = refusal_of(write_log("shuffled.log", lines));
    EXPECT_GE(r.line, 2U) << r.message;
}

TEST(CandumpReplayReader, EqualTimeStampsAreAccepted) {
    const std::string path = write_log("equal.log", sensor_lines(50));  // two frames per stamp
    const host_sim::CandumpLog log = host_sim::read_candump_log(path);
    EXPECT_EQ(log.records.size(), 100U);
    EXPECT_FALSE(log.box_log);
}

TEST(CandumpReplayReader, ABoxLogKeepsItsReceivedAndItsOwnFramesEachInTimeOrder) {
    // scopekin-box --record writes a period's received frames, then its own frames stamped with
    // the period's time, read before those frames were: 100 µs earlier here.  Accepted.
    hal::CanFrame estimate{};
    estimate.id = protocol::kKineticEstimateId;
    estimate.length = 8;
    std::vector<std::string> lines;
    for (std::uint32_t k = 0; k < 4; ++k) {
        const std::uint64_t period = kStartUs + std::uint64_t{k} * 5000U;
        lines.push_back(line_of(period + 100U, force_frame(k)));
        lines.push_back(line_of(period, estimate));
    }
    const host_sim::CandumpLog log = host_sim::read_candump_log(write_log("box.log", lines));
    EXPECT_TRUE(log.box_log);
    EXPECT_EQ(log.records.size(), 8U);

    // A period of the box earlier than the one before it: refused, naming the box's line before.
    std::vector<std::string> periods_back = lines;
    periods_back.push_back(line_of(kStartUs + 3U * 5000U - 1U, estimate));
    Refusal r = refusal_of(write_log("box_period_back.log", periods_back));
    EXPECT_EQ(r.line, 9U) << r.message;
    EXPECT_NE(r.message.find("before line 8's"), std::string::npos) << r.message;

    // A received frame earlier than the received frame before it: refused, naming that line.
    std::vector<std::string> inputs_back = lines;
    inputs_back.push_back(line_of(kStartUs + 3U * 5000U + 99U, force_frame(4)));
    r = refusal_of(write_log("box_input_back.log", inputs_back));
    EXPECT_EQ(r.line, 9U) << r.message;
    EXPECT_NE(r.message.find("before line 7's"), std::string::npos) << r.message;
}

TEST(CandumpReplayReader, AGapLongerThanTheBoundIsRefusedNamingTheLine) {
    std::vector<std::string> lines = sensor_lines(100);  // 100 ms
    // One frame 10^9 s later: a 5 ms period across it would be 2 * 10^11 periods.
    lines.push_back(line_of(kStartUs + 1'000'000'000'000'000ULL, force_frame(100)));
    const std::string path = write_log("gap.log", lines);
    const Refusal r = refusal_of(path);
    EXPECT_EQ(r.line, 201U) << r.message;
    EXPECT_NE(r.message.find("line 201"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("--max-gap-s"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("60"), std::string::npos) << r.message;
}

TEST(CandumpReplayReader, TheGapBoundIsDefaultSixtySecondsAndCanBeRaised) {
    std::vector<std::string> at_bound = sensor_lines(10);
    const std::uint64_t last = kStartUs + 9000U;
    at_bound.push_back(line_of(last + 60'000'000U, force_frame(10)));  // exactly 60 s: fine
    EXPECT_EQ(refusal_of(write_log("gap60.log", at_bound)).line, 0U);

    std::vector<std::string> over = sensor_lines(10);
    over.push_back(line_of(last + 60'000'001U, force_frame(10)));  // 1 µs more: refused
    const std::string path = write_log("gap60plus.log", over);
    EXPECT_EQ(refusal_of(path).line, 21U);

    host_sim::CandumpReadOptions raised;
    raised.max_gap_us = 120'000'000U;
    EXPECT_EQ(refusal_of(path, raised).line, 0U);
    // ... and the replay across the raised bound is finite: a period every 5 ms of the log.
    const host_sim::CandumpLog log = host_sim::read_candump_log(path, raised);
    const host_sim::ReplayResult result = host_sim::replay_candump(log, nullptr);
    EXPECT_EQ(result.periods, (60'000'001U + 9000U) / 5000U + 1U);
}

TEST(CandumpReplay, AFloodOfForeignFramesChangesNoOutput) {
    // 3 s of both handle sensors at 1 kHz, alone and beside 100 foreign frames per ms (the
    // box reads at most 128 frames per period; the flood brings 500 per period).
    const host_sim::CandumpLog clean = sensor_log(3000, 0);
    const host_sim::CandumpLog flood = sensor_log(3000, 100);
    std::vector<std::int32_t> clean_tip;
    std::vector<std::uint32_t> clean_flags;
    const host_sim::ReplayResult a =
        host_sim::replay_candump(clean, [&](const scopekin::host_sim::BoxPeriod& p) {
            clean_tip.push_back(p.outputs->tip_path_mm.raw());
            clean_flags.push_back(p.outputs->fault_flags);
        });
    std::vector<std::int32_t> flood_tip;
    std::vector<std::uint32_t> flood_flags;
    const host_sim::ReplayResult b =
        host_sim::replay_candump(flood, [&](const scopekin::host_sim::BoxPeriod& p) {
            flood_tip.push_back(p.outputs->tip_path_mm.raw());
            flood_flags.push_back(p.outputs->fault_flags);
        });
    ASSERT_EQ(a.periods, b.periods);
    ASSERT_EQ(clean_tip.size(), flood_tip.size());
    // The tip at 3 s: the handle moved 100 -> 250 mm; the estimate follows it (the same log
    // without the flood is the reference).
    const double tip_clean_mm = clean_tip.back() / 65536.0;
    const double tip_flood_mm = flood_tip.back() / 65536.0;
    EXPECT_GT(tip_clean_mm, 240.0);
    // The filter holds the flood back before the box: every period's output is the same.
    EXPECT_NEAR(tip_flood_mm, tip_clean_mm, 0.0) << "flood moved the tip estimate";
    EXPECT_EQ(flood_tip, clean_tip);
    EXPECT_EQ(flood_flags, clean_flags);
    EXPECT_EQ(b.frames_fed, a.frames_fed);
    EXPECT_EQ(b.frames_filtered, 3000U * 100U);
    EXPECT_EQ(a.frames_filtered, 0U);
}

TEST(CandumpReplay, ItsRecordIsABoxLogThatReplaysToTheSameFrames) {
    // `scopekin replay --record`: what the replayed box received (the frames its filter passed)
    // and sent, in a box log's order; replayed as a box log, every output frame compares equal.
    const host_sim::CandumpLog sensors = sensor_log(1000, 2);
    host_sim::CandumpLog record;
    record.box_log = true;
    const host_sim::ReplayResult first =
        host_sim::replay_candump(sensors, nullptr, [&](const hal::CandumpRecord& r) {
            record.records.push_back(r);
            record.lines.push_back(record.records.size());
        });
    std::size_t estimates = 0, foreign = 0, received = 0;
    std::uint64_t previous_us = 0;
    for (const hal::CandumpRecord& r : record.records) {
        EXPECT_GE(r.timestamp_us, previous_us) << "a box log is in time order";
        previous_us = r.timestamp_us;
        EXPECT_STREQ(r.interface.data(), "can0");
        if (r.frame.id == protocol::kKineticEstimateId) ++estimates;
        if (r.frame.id >= 0x300U) ++foreign;
        if (host_sim::is_input(r)) ++received;
    }
    EXPECT_EQ(estimates, first.periods);  // one KineticEstimate per period
    EXPECT_EQ(foreign, 0U);               // the filter held them back, as the kernel would
    EXPECT_EQ(received, first.frames_fed);
    const host_sim::ReplayResult again = host_sim::replay_candump(record, nullptr);
    EXPECT_EQ(again.periods, first.periods);
    EXPECT_GT(again.compared_frames, 4U * first.periods);
    EXPECT_EQ(again.differing_frames, 0U) << again.first_difference;
}
