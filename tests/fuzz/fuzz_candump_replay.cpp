// fuzz_candump_replay.cpp — libFuzzer target: the candump file reader of `scopekin replay`
// (host_sim/replay/candump_replay.hpp: read_candump_log, with its time order and gap checks) on
// any file content, and replay_candump (the box's receive filter, its periods) on what it accepts.
// The input is written to a file under /dev/shm (or $TMPDIR) and read from there, as the command
// reads it.  A log whose replay would run more than 400 periods is read, not replayed (bounded
// time per input).
//
// Oracles (__builtin_trap() on violation, on top of ASan/UBSan):
//   * a refusal is a CandumpLineError (no other exception) whose message starts with the file's
//     name, is at most 600 characters and names a line of the file (or 0);
//   * accepted: at least one record; one file line per record, increasing; box_log exactly when
//     a standard 0x181 frame is in it; no time stamp more than max_gap_us after the one before;
//     a sensor log in time order, a box log's received frames and own frames each in time order;
//   * the records written back (format_candump_line) are read again as the same log;
//   * replay: frames_fed + frames_filtered == the log's input frames, frames_fed those the box's
//     receive filter passes (0x110, 0x111, error frames); periods: a box log one per
//     KineticEstimate line, a sensor log one per 5 ms from the first frame up to the last input
//     plus one; differing <= compared; every period's fault bits are BoxFault bits and its
//     estimator flags known ones; period times never go back.
#include <unistd.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "fuzz_support.hpp"
#include "host_sim/replay/candump_replay.hpp"
#include "kinetics/kinetics_io.hpp"
#include "messages/box_faults.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace {

namespace host_sim = scopekin::host_sim;
namespace hal = scopekin::hal;
namespace protocol = scopekin::protocol;

std::array<std::string, 2> paths;  // the two scratch files (the log, the log written back)

/// The scratch file `name` ("a.log", "b.log") of this process (removed after each input).
const std::string& scratch_file(const char* name) {
    static const std::string directory = [] {
        const char* tmp = std::getenv("TMPDIR");
        return std::string(access("/dev/shm", W_OK) == 0 ? "/dev/shm"
                                                         : (tmp != nullptr ? tmp : "/tmp"));
    }();
    std::string& path = paths[name[0] == 'a' ? 0 : 1];
    if (path.empty()) {
        path = directory + "/scopekin_fuzz_candump_" + std::to_string(getpid()) + "_" + name;
    }
    return path;
}

void write_file(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    require(static_cast<bool>(out));
}

bool same_record(const hal::CandumpRecord& a, const hal::CandumpRecord& b) {
    return a.timestamp_us == b.timestamp_us && a.interface == b.interface &&
           a.frame.id == b.frame.id && a.frame.extended == b.frame.extended &&
           a.frame.remote == b.frame.remote && a.frame.error == b.frame.error &&
           a.frame.length == b.frame.length && a.frame.data == b.frame.data;
}

bool is_estimate_line(const hal::CandumpRecord& r) {
    return !r.frame.error && !r.frame.extended && r.frame.id == protocol::kKineticEstimateId;
}

void check_log(const host_sim::CandumpLog& log, const host_sim::CandumpReadOptions& options) {
    const std::size_t n = log.records.size();
    require(n > 0U && log.lines.size() == n);
    bool estimate = false;
    std::array<std::size_t, 2> last{n, n};  // [input, output]
    for (std::size_t i = 0; i < n; ++i) {
        const hal::CandumpRecord& r = log.records[i];
        estimate = estimate || is_estimate_line(r);
        if (i > 0) {
            require(log.lines[i] > log.lines[i - 1]);
            const std::uint64_t before = log.records[i - 1].timestamp_us;
            require(r.timestamp_us <= before || r.timestamp_us - before <= options.max_gap_us);
        }
        const std::size_t stream = log.box_log && !host_sim::is_input(r) ? 1U : 0U;
        if (last[stream] < n) require(r.timestamp_us >= log.records[last[stream]].timestamp_us);
        last[stream] = i;
    }
    require(estimate == log.box_log);
}

void check_error(const host_sim::CandumpLineError& error, const std::string& path,
                 const std::string& text) {
    const std::string message = error.what();
    require(message.rfind(path, 0) == 0);
    require(message.size() <= 600U);
    std::size_t lines = 1;
    for (const char c : text)
        lines += c == '\n' ? 1U : 0U;
    require(error.line() <= lines);
}

void check_replay(const host_sim::CandumpLog& log) {
    std::uint64_t inputs = 0;
    std::uint64_t passed = 0;
    std::uint64_t estimates = 0;
    std::uint64_t last_input_us = 0;
    for (const hal::CandumpRecord& r : log.records) {
        if (host_sim::is_input(r)) {
            ++inputs;
            last_input_us = r.timestamp_us;
            const bool handle_id = r.frame.id == protocol::kHandleForceTorqueId ||
                                   r.frame.id == protocol::kInsertionRollId;
            if (r.frame.error || (!r.frame.extended && !r.frame.remote && handle_id)) ++passed;
        }
        if (is_estimate_line(r)) ++estimates;
    }
    std::uint64_t expected_periods = estimates;
    if (!log.box_log) {
        const std::uint64_t first = log.records.front().timestamp_us + host_sim::kBoxPeriodUs;
        expected_periods = 1U;
        if (inputs > 0U && last_input_us > first) {
            expected_periods += (last_input_us - first - 1U) / host_sim::kBoxPeriodUs + 1U;
        }
    }
    if (expected_periods > 400U) return;  // bounded time per input

    std::uint64_t periods_seen = 0;
    std::uint64_t last_time = 0;
    const host_sim::ReplayResult result =
        host_sim::replay_candump(log, [&](const host_sim::BoxPeriod& period) {
            require(period.time_us >= last_time);
            last_time = period.time_us;
            require(period.outputs != nullptr);
            require((period.box_faults & ~scopekin::messages::kAllBoxFaults) == 0U);
            require((period.outputs->fault_flags & ~scopekin::kinetics::kAllFaultFlags) == 0U);
            ++periods_seen;
        });
    require(result.periods == periods_seen);
    require(result.periods == expected_periods);
    require(result.frames_fed + result.frames_filtered == inputs);
    require(result.frames_fed == passed);
    require(result.differing_frames <= result.compared_frames);
    require(result.first_difference.empty() == (result.differing_frames == 0U));
}

}  // namespace

namespace {

/// Removes the scratch files when an input is done (libFuzzer's exit runs no atexit handler).
struct ScratchCleanup {
    ScratchCleanup() = default;
    ScratchCleanup(const ScratchCleanup&) = delete;
    ScratchCleanup& operator=(const ScratchCleanup&) = delete;
    ~ScratchCleanup() {
        for (const std::string& path : paths) {
            if (!path.empty()) (void)std::remove(path.c_str());
        }
    }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const ScratchCleanup cleanup;
    const std::string text(reinterpret_cast<const char*>(data), size);
    const std::string& path = scratch_file("a.log");
    write_file(path, text);
    const host_sim::CandumpReadOptions options{};
    host_sim::CandumpLog log;
    try {
        log = host_sim::read_candump_log(path, options);
    } catch (const host_sim::CandumpLineError& error) {
        check_error(error, path, text);
        return 0;
    } catch (...) {
        require(false);  // only CandumpLineError may leave the reader
    }
    check_log(log, options);

    // Written back, read again: the same log.
    std::string written;
    for (const hal::CandumpRecord& record : log.records) {
        std::array<char, hal::kCandumpLineCapacity> line{};
        const std::size_t length = hal::format_candump_line(record, line);
        require(length > 0U);
        written.append(line.data(), length);
    }
    const std::string& again_path = scratch_file("b.log");
    write_file(again_path, written);
    host_sim::CandumpLog again;
    try {
        again = host_sim::read_candump_log(again_path, options);
    } catch (...) {
        require(false);
    }
    require(again.records.size() == log.records.size() && again.box_log == log.box_log);
    for (std::size_t i = 0; i < log.records.size(); ++i) {
        require(same_record(again.records[i], log.records[i]));
    }

    check_replay(log);
    return 0;
}
