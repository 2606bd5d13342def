#pragma once
// `scopekin replay`: a candump log (candump -L / canplayer format) through the unmodified
// firmware. Two kinds of log:
//  * a box log (it holds the box's KineticEstimate frames, 0x181): what `scopekin-box --record`
//    writes. Every line is in the order the box saw it: the frames it received in a period, then
//    the frames it sent, which carry the period's release time (hal/linux/recording_can_bus.hpp).
//    The replay gives the box the same frames with the same timestamps and runs each period at
//    the recorded time, then compares what the box sends with what was recorded (KineticEstimate,
//    ContactSummary, Alarms, EstimateEvidence, StationForces; BoxStatus and BoxCounters carry the live box's
//    overrun and bus counters, which a replay cannot have).
//  * a sensor log (no 0x181): the handle sensors' frames only; the box runs every 5 ms from the
//    first frame's time, each period after the frames stamped at or before it.
// Either way the box gets only the frames its receive filter passes (the handle sensors' 0x110
// and 0x111, and error frames: SensorBox sets the filter at init), as the kernel filters them
// for scopekin-box; the rest are counted in ReplayResult::frames_filtered.
// The reader takes a log only in time order: in a sensor log no time stamp may be earlier than
// the line before it (equal is fine); in a box log the received frames and the box's own frames
// are each in time order (the box's frames carry their period's time, taken before the period
// read its frames, so they may be stamped a little before the received lines above them).  No
// gap between two lines may be longer than CandumpReadOptions::max_gap_us (`--max-gap-s`,
// default 60 s), so a replay runs at most max_gap_us / 5 ms periods per line: never an endless
// run or unbounded output.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hal/candump/candump_log.hpp"
#include "host_sim/simulator/firmware_loop.hpp"

namespace scopekin::host_sim {

/// A log line that could not be parsed.
struct CandumpLineError : std::runtime_error {
    CandumpLineError(const std::string& message, std::size_t line)
        : std::runtime_error(message), line_(line) {}
    std::size_t line() const { return line_; }

private:
    std::size_t line_;
};

struct CandumpLog {
    std::vector<hal::CandumpRecord> records;
    std::vector<std::size_t> lines;  ///< the file line of each record
    bool box_log = false;
};

/// The largest gap between two lines `--max-gap-s` may allow: one hour (720,000 periods).
inline constexpr double kMaxGapLimit_s = 3600.0;

struct CandumpReadOptions {
    /// Longest accepted time between two consecutive lines (`--max-gap-s`; default 60 s).
    std::uint64_t max_gap_us = 60'000'000;
};

/// Reads a candump log; throws CandumpLineError (naming the file and line) for a malformed line,
/// a time stamp earlier than the line before it, and a gap longer than options.max_gap_us.
CandumpLog read_candump_log(const std::string& path, const CandumpReadOptions& options = {});

struct ReplayResult {
    std::uint64_t periods = 0;
    std::uint64_t frames_fed = 0;       ///< frames given to the box
    std::uint64_t frames_filtered = 0;  ///< frames its receive filter held back (foreign ids)
    std::uint64_t compared_frames = 0;  ///< box log: recorded output frames compared
    std::uint64_t differing_frames = 0;
    /// Box log: periods whose recorded EstimateEvidence says the box fused its EM tracker's tip
    /// (TipFromTracker, protocol 1.3). A CAN log does not hold the tracker's serial samples, so
    /// only those periods' Alarms frames (which do not read the tip) are compared; the estimate,
    /// the contact summary, the evidence and the station frames carry the fused tip.
    std::uint64_t tracker_periods = 0;
    std::uint64_t uncomparable_frames = 0;  ///< recorded frames of those periods not compared
    /// Alarms frames from the first tracker period on, compared without SelfLockAlarm and
    /// SelfLockRaised: with the tracker the loop alarm's gate reads the tracker's tip
    /// (slack_excess.hpp), and the raise counter carries any difference on.
    std::uint64_t alarms_without_self_lock = 0;
    std::string first_difference;  ///< empty if none
};

/// Every frame the replayed box received (those its filter passed) and sent, in the order of a
/// box log (`scopekin replay --record`): the received ones as the log stamps them, the sent ones
/// with their period's time and the log's first interface.
using ReplayFrameTap = std::function<void(const hal::CandumpRecord&)>;

/// Replays the log through a box; `on_period` sees every period (time, outputs), `on_frame`
/// (optional) every frame in and out.
ReplayResult replay_candump(const CandumpLog& log,
                            const std::function<void(const BoxPeriod&)>& on_period,
                            const ReplayFrameTap& on_frame = {});

/// True for the ids the box sends.
bool is_box_output_id(std::uint32_t id);
/// True for a frame the box receives: anything but the box's own frames.
bool is_input(const hal::CandumpRecord& record);

}  // namespace scopekin::host_sim
