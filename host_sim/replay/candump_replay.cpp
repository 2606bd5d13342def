#include "host_sim/replay/candump_replay.hpp"

#include <algorithm>
#include <cstdio>
#include <deque>
#include <fstream>
#include <memory>
#include <span>
#include <sstream>

#include "executive/sensor_box.hpp"
#include "kinetics/default_reduced_tables.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace scopekin::host_sim {
namespace {

/// A CAN bus that hands the box the log's frames and keeps what the box sends.  It holds back
/// the frames the box's receive filter does not pass, as the kernel does for scopekin-box.
class ReplayCanBus final : public hal::CanBus {
public:
    hal::CanStatus set_receive_filter(std::span<const hal::CanIdFilter> filters) override {
        return filter_.assign(filters) ? hal::CanStatus::ok : hal::CanStatus::invalid;
    }
    /// Queues a frame of the log for the box; false if the box's filter holds it back.
    bool offer(const hal::CandumpRecord& record) {
        if (!filter_.passes(record.frame)) return false;
        queue.push_back({record.frame, record.timestamp_us});
        return true;
    }
    hal::CanStatus send(const hal::CanFrame& frame, std::uint32_t /*timeout_us*/) override {
        sent.push_back(frame);
        ++counters_.sent;
        return hal::CanStatus::ok;
    }
    hal::CanStatus receive(hal::ReceivedCanFrame& received, std::uint32_t /*timeout_us*/) override {
        if (queue.empty()) return hal::CanStatus::timeout;
        received = queue.front();
        queue.pop_front();
        hal::count_received_frame(counters_, received.frame);
        return hal::CanStatus::ok;
    }
    hal::CanCounters counters() const override { return counters_; }

    std::deque<hal::ReceivedCanFrame> queue;
    std::vector<hal::CanFrame> sent;

private:
    hal::CanCounters counters_{};
    hal::CanReceiveFilter filter_{};
};

bool compared_output(std::uint32_t id) {
    return id == protocol::kKineticEstimateId || id == protocol::kContactSummaryId ||
           id == protocol::kAlarmsId || id == protocol::kEstimateEvidenceId ||
           id == protocol::kStationForcesId;
}

/// A candump time stamp as the log writes it: seconds.microseconds.
std::string stamp_text(std::uint64_t time_us) {
    char b[32];
    std::snprintf(b, sizeof b, "%llu.%06llu", static_cast<unsigned long long>(time_us / 1000000U),
                  static_cast<unsigned long long>(time_us % 1000000U));
    return b;
}

/// A duration in µs as exact seconds, trailing zeros dropped ("60", "0.0005", "1000000000").
std::string seconds_text(std::uint64_t duration_us) {
    std::string text = stamp_text(duration_us);
    while (text.back() == '0')
        text.pop_back();
    if (text.back() == '.') text.pop_back();
    return text;
}

std::string frame_text(const hal::CanFrame& f) {
    std::string s;
    char b[16];
    std::snprintf(b, sizeof b, "%03X#", static_cast<unsigned>(f.id));
    s = b;
    for (std::size_t i = 0; i < f.length; ++i) {
        std::snprintf(b, sizeof b, "%02X", static_cast<unsigned>(f.data[i]));
        s += b;
    }
    return s;
}

bool same_frame(const hal::CanFrame& a, const hal::CanFrame& b) {
    return a.length == b.length &&
           std::equal(a.data.begin(), a.data.begin() + a.length, b.data.begin());
}

/// Two Alarms frames equal but for SelfLockAlarm and SelfLockRaised.
bool same_but_self_lock(const hal::CanFrame& a, const hal::CanFrame& b) {
    protocol::Alarms x{}, y{};
    if (protocol::decode(a, x) != protocol::DecodeResult::ok ||
        protocol::decode(b, y) != protocol::DecodeResult::ok) {
        return same_frame(a, b);
    }
    x.self_lock = y.self_lock = false;
    x.self_lock_raised = y.self_lock_raised = 0;
    return same_frame(protocol::encode(x), protocol::encode(y));
}

}  // namespace

bool is_box_output_id(std::uint32_t id) {
    return id == protocol::kBoxStatusId || id == protocol::kKineticEstimateId ||
           id == protocol::kContactSummaryId || id == protocol::kAlarmsId ||
           id == protocol::kBoxCountersId || id == protocol::kEstimateEvidenceId ||
           id == protocol::kStationForcesId;
}

/// A frame the box receives (anything but the box's own outputs).
bool is_input(const hal::CandumpRecord& r) {
    return r.frame.error || r.frame.extended || !is_box_output_id(r.frame.id);
}

namespace {

/// Refuses line `number` (time stamp `now`) for its relation to record `previous` of `log`.
[[noreturn]] void refuse_time_stamp(const std::string& path, const CandumpLog& log,
                                    std::size_t previous, std::size_t number, std::uint64_t now,
                                    const char* relation, const std::string& reason) {
    const std::uint64_t before = log.records[previous].timestamp_us;
    const std::uint64_t apart = now > before ? now - before : before - now;
    throw CandumpLineError(path + ": line " + std::to_string(number) + ": time stamp " +
                               stamp_text(now) + " is " + seconds_text(apart) + relation +
                               " line " + std::to_string(log.lines[previous]) + "'s " +
                               stamp_text(before) + ": " + reason,
                           number);
}

}  // namespace

CandumpLog read_candump_log(const std::string& path, const CandumpReadOptions& options) {
    std::ifstream in(path);
    if (!in) throw CandumpLineError(path + ": cannot be read", 0);
    CandumpLog log;
    std::string line;
    std::size_t number = 0;
    while (std::getline(in, line)) {
        ++number;
        hal::CandumpRecord record{};
        const hal::CandumpParse parse = hal::parse_candump_line(line, record);
        if (parse == hal::CandumpParse::blank) continue;
        if (parse != hal::CandumpParse::ok)
            throw CandumpLineError(
                path + ": line " + std::to_string(number) + ": " + hal::describe(parse) +
                    " (expected candump -L format: '(1700000000.123456) can0 110#0102030405')",
                number);
        if (!log.records.empty() && record.timestamp_us > log.records.back().timestamp_us &&
            record.timestamp_us - log.records.back().timestamp_us > options.max_gap_us)
            refuse_time_stamp(
                path, log, log.records.size() - 1U, number, record.timestamp_us, " s after",
                "longer than the largest gap, --max-gap-s " + seconds_text(options.max_gap_us) +
                    " s (a replay runs the box every 5 ms across it; raise "
                    "--max-gap-s if the pause is real)");
        if (!record.frame.error && !record.frame.extended &&
            record.frame.id == protocol::kKineticEstimateId)
            log.box_log = true;
        log.records.push_back(record);
        log.lines.push_back(number);
    }
    if (log.records.empty()) throw CandumpLineError(path + ": no CAN frames in the log", 0);
    // Time order.  A sensor log: no line before the one above it.  A box log: the frames the box
    // received in time order, and its own frames (stamped with their period's time, which the
    // recorder takes before it reads that period's frames) in time order; only the two may
    // interleave out of order.
    std::size_t last[2] = {log.records.size(), log.records.size()};  // [input, output]
    for (std::size_t i = 0; i < log.records.size(); ++i) {
        const std::size_t stream = log.box_log && !is_input(log.records[i]) ? 1U : 0U;
        const std::size_t previous = last[stream];
        if (previous < i && log.records[i].timestamp_us < log.records[previous].timestamp_us)
            refuse_time_stamp(path, log, previous, log.lines[i], log.records[i].timestamp_us,
                              " s before",
                              "a candump log must be in time order (equal time stamps are fine; "
                              "a reversed, shuffled or spliced log is not one recording)");
        last[stream] = i;
    }
    return log;
}

ReplayResult replay_candump(const CandumpLog& log,
                            const std::function<void(const BoxPeriod&)>& on_period,
                            const ReplayFrameTap& on_frame) {
    ReplayResult result;
    hal::CandumpRecord sent_record{};  // the box's frames as a box log stamps them
    if (!log.records.empty()) sent_record.interface = log.records.front().interface;
    auto bus = std::make_unique<ReplayCanBus>();
    auto box = std::make_unique<executive::SensorBox>();
    executive::BoxConfig config{};
    config.period_us = kBoxPeriodUs;
    config.kinetics = kinetics::default_config();  // the default tables and trees
    (void)box->init(config, *bus, nullptr);

    auto run = [&](std::uint64_t time_us) {
        bus->sent.clear();
        box->run_period(time_us, 0);
        ++result.periods;
        if (on_frame) {
            sent_record.timestamp_us = time_us;
            for (const hal::CanFrame& f : bus->sent) {
                sent_record.frame = f;
                on_frame(sent_record);
            }
        }
        if (on_period) on_period({time_us, &box->outputs(), box->box_faults(), box.get()});
    };

    auto offer = [&](const hal::CandumpRecord& r) {
        const bool passed = bus->offer(r);
        ++(passed ? result.frames_fed : result.frames_filtered);
        if (passed && on_frame) on_frame(r);
    };

    std::size_t tracker_shadow = 0;  // periods still carrying a fused tip (see below)
    bool tracker_seen = false;       // the loop alarm's state may carry the tracker's gate
    if (log.box_log) {
        std::size_t i = 0;
        const std::size_t n = log.records.size();
        while (i < n) {
            const hal::CandumpRecord& r = log.records[i];
            if (is_input(r)) {
                offer(r);
                ++i;
                continue;
            }
            if (r.frame.id !=
                protocol::kKineticEstimateId) {  // outputs before the first full period
                ++i;
                continue;
            }
            run(r.timestamp_us);
            // Compare this period's recorded outputs (up to the next input line or next period)
            // with the replayed frames of the same identifier, in order: a log of an older
            // protocol without some message (1.2 had no EstimateEvidence) still compares.
            std::vector<hal::CanFrame> replayed;
            for (const hal::CanFrame& f : bus->sent)
                if (compared_output(f.id)) replayed.push_back(f);
            std::vector<bool> used(replayed.size(), false);
            bool tracker_period = false;
            for (std::size_t k = i; k < n && !is_input(log.records[k]); ++k) {
                const hal::CanFrame& recorded = log.records[k].frame;
                if (k > i && recorded.id == protocol::kKineticEstimateId) break;
                protocol::EstimateEvidence evidence{};
                if (recorded.id == protocol::kEstimateEvidenceId &&
                    protocol::decode(recorded, evidence) == protocol::DecodeResult::ok &&
                    evidence.tip_from_tracker) {
                    tracker_period = true;
                }
            }
            // The tip velocity averages the last kVelocityWindow published tips: the periods
            // right after the tracker's carry its fused tips too.
            if (tracker_period) {
                tracker_shadow = kinetics::kVelocityWindow;
            } else if (tracker_shadow > 0U) {
                --tracker_shadow;
                tracker_period = true;
            }
            if (tracker_period) ++result.tracker_periods;
            tracker_seen = tracker_seen || tracker_period;
            std::size_t j = i;
            for (; j < n && !is_input(log.records[j]); ++j) {
                const hal::CanFrame& recorded = log.records[j].frame;
                if (j > i && recorded.id == protocol::kKineticEstimateId) break;
                if (!compared_output(recorded.id)) continue;
                if (tracker_period && recorded.id != protocol::kAlarmsId) {
                    ++result.uncomparable_frames;
                    continue;
                }
                ++result.compared_frames;
                std::size_t match = replayed.size();
                for (std::size_t k = 0; k < replayed.size(); ++k) {
                    if (!used[k] && replayed[k].id == recorded.id) {
                        match = k;
                        break;
                    }
                }
                if (match < replayed.size()) used[match] = true;
                const bool without_self_lock = tracker_seen && recorded.id == protocol::kAlarmsId;
                if (without_self_lock) ++result.alarms_without_self_lock;
                const bool same = match < replayed.size() &&
                                  (without_self_lock ? same_but_self_lock(recorded, replayed[match])
                                                     : same_frame(recorded, replayed[match]));
                if (!same) {
                    ++result.differing_frames;
                    if (result.first_difference.empty())
                        result.first_difference =
                            "line " + std::to_string(log.lines[j]) + ": recorded " +
                            frame_text(recorded) + ", replayed " +
                            (match < replayed.size() ? frame_text(replayed[match]) : "nothing");
                }
            }
            i = j;
        }
        return result;
    }

    // Sensor log: periods every 5 ms from the first frame.
    std::uint64_t next = log.records.front().timestamp_us + kBoxPeriodUs;
    for (const hal::CandumpRecord& r : log.records) {
        if (!is_input(r)) continue;
        while (next < r.timestamp_us) {
            run(next);
            next += kBoxPeriodUs;
        }
        offer(r);
    }
    run(next);
    return result;
}

}  // namespace scopekin::host_sim
