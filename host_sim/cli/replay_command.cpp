#include "host_sim/cli/replay_command.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "hal/candump/candump_log.hpp"
#include "host_sim/cli/cli_support.hpp"
#include "host_sim/cli/live_run.hpp"
#include "host_sim/replay/candump_replay.hpp"
#include "host_sim/simulator/box_observer.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

struct ReplayOptions {
    std::string log;
    std::string out;
    double max_gap_s = 60.0;
    std::string record;  ///< the replayed box's log (its frames in and out), candump format
    bool quiet = false;
};

/// `--record FILE`: every frame the replayed box received and sent, as `scopekin-box --record`
/// writes them (a box log: `scopekin display` shows it, `scopekin replay` replays it).
class BoxLogWriter {
public:
    explicit BoxLogWriter(const std::string& path) : file_(path) {}
    void write(const hal::CandumpRecord& record) {
        std::array<char, hal::kCandumpLineCapacity> line{};
        const std::size_t n = hal::format_candump_line(record, line);
        file_.stream().write(line.data(), static_cast<std::streamsize>(n));
    }
    void finish() { file_.finish(true); }

private:
    PartFile file_;
};

/// --max-gap-s: seconds, finite, above 0 and at most host_sim::kMaxGapLimit_s.
const CLI::Validator kGapSeconds(
    [](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(value) || value <= 0.0 ||
            value > host_sim::kMaxGapLimit_s) {
            const std::string shown = text.size() > 40 ? text.substr(0, 40) + "..." : text;
            return "must be a number of seconds above 0 and at most 3600, not '" + shown + "'";
        }
        return {};
    },
    "SECONDS in (0, 3600]");

/// What the recorded box said about itself (a box log): the fault bits of its BoxStatus frames
/// (sent every 20 periods and at once when a bit changes: frames with each bit set and the time
/// of the first) and the last value of each BoxCounters index. These carry what a replay cannot
/// reproduce: the live box's overruns, kernel drops and bus faults.
Json recorded_box_state(const host_sim::CandumpLog& log) {
    static constexpr std::array<const char*, protocol::kBoxCounterCount> kCounterNames{
        "can_received",
        "can_dropped",
        "can_error_frames",
        "can_bus_off",
        "can_send_failures",
        "bad_length",
        "unknown_id",
        "out_of_range",
        "counter_gaps",
        "stale_events",
        "serial_frames",
        "serial_bad_frames",
        "serial_bytes_discarded",
        "period_overruns",
        "steps",
        "sensor_status",
        "receive_backlog"};
    std::uint64_t status_frames = 0;
    std::array<std::uint64_t, 16> driver_frames{};
    std::array<std::uint64_t, 8> tracker_frames{};
    Json driver_first = Json::object(), tracker_first = Json::object();
    Json counters = Json::object();
    std::uint8_t last_overruns = 0;
    for (const hal::CandumpRecord& r : log.records) {
        const double t = static_cast<double>(r.timestamp_us) / 1e6;
        protocol::BoxStatus status;
        protocol::BoxCounter counter;
        if (protocol::decode(r.frame, status) == protocol::DecodeResult::ok) {
            ++status_frames;
            last_overruns = status.period_overruns;
            for (std::size_t k = 0; k < driver_frames.size(); ++k)
                if ((status.driver_faults & (1U << k)) != 0U && driver_frames[k]++ == 0)
                    driver_first[host_sim::box_fault_names()[k]] = t;
            for (std::size_t k = 0; k < tracker_frames.size(); ++k)
                if ((status.tracker_faults & (1U << k)) != 0U && tracker_frames[k]++ == 0)
                    tracker_first[host_sim::tracker_fault_names()[k]] = t;
        } else if (protocol::decode(r.frame, counter) == protocol::DecodeResult::ok) {
            const auto index = static_cast<std::size_t>(counter.index);
            if (index < kCounterNames.size()) counters[kCounterNames[index]] = counter.value;
        }
    }
    Json out;
    out["status_frames"] = status_frames;
    Json driver = Json::object(), tracker = Json::object();
    for (std::size_t k = 0; k < driver_frames.size(); ++k)
        if (driver_frames[k] > 0) driver[host_sim::box_fault_names()[k]] = driver_frames[k];
    for (std::size_t k = 0; k < tracker_frames.size(); ++k)
        if (tracker_frames[k] > 0) tracker[host_sim::tracker_fault_names()[k]] = tracker_frames[k];
    out["fault_frames"] = driver;
    out["fault_first_s"] = driver_first;
    out["tracker_fault_frames"] = tracker;
    out["tracker_fault_first_s"] = tracker_first;
    out["period_overruns_last"] = last_overruns;
    out["counters_last"] = counters;
    return out;
}

int run_replay(const ReplayOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    host_sim::CandumpLog log;
    try {
        host_sim::CandumpReadOptions read_options;
        read_options.max_gap_us = static_cast<std::uint64_t>(std::ceil(options.max_gap_s * 1e6));
        log = host_sim::read_candump_log(options.log, read_options);
    } catch (const host_sim::CandumpLineError& e) {
        std::cerr << "scopekin replay: invalid log: " << e.what() << "\n";
        return 2;
    }
    try {
        const fs::path dir(options.out);
        prepare_directory(dir, {"summary.json", "firmware.csv", "firmware.incomplete.csv"});
        PartFile firmware_csv(dir / "firmware.csv", dir / "firmware.incomplete.csv");
        host_sim::BoxObserver observer(&firmware_csv.stream());
        if (!options.quiet)
            std::cerr << "replaying " << log.records.size() << " frames of " << options.log << " ("
                      << (log.box_log ? "a box log: periods at the recorded times, outputs compared"
                                      : "a sensor log: a period every 5 ms")
                      << ")" << std::endl;
        std::unique_ptr<BoxLogWriter> record;
        if (!options.record.empty()) record = std::make_unique<BoxLogWriter>(options.record);
        const host_sim::ReplayResult r = host_sim::replay_candump(
            log, [&](const host_sim::BoxPeriod& p) { observer.observe(p); },
            record
                ? host_sim::ReplayFrameTap([&](const hal::CandumpRecord& f) { record->write(f); })
                : host_sim::ReplayFrameTap());
        firmware_csv.finish(true);
        if (record) record->finish();
        const Json box = observer.to_json();
        Json s;
        s["log"] = options.log;
        s["kind"] = log.box_log ? "box_log" : "sensor_log";
        s["frames"] = log.records.size();
        s["frames_fed"] = r.frames_fed;
        s["frames_filtered"] = r.frames_filtered;
        s["periods"] = r.periods;
        if (log.box_log) {
            s["compared_frames"] = r.compared_frames;
            s["differing_frames"] = r.differing_frames;
            s["tracker_periods"] = r.tracker_periods;
            s["uncomparable_frames"] = r.uncomparable_frames;
            s["alarms_without_self_lock"] = r.alarms_without_self_lock;
            s["identical"] = r.differing_frames == 0 && r.compared_frames > 0;
            s["first_difference"] = r.first_difference;
        }
        s["alarms"] = box["alarms"];
        s["firmware"] = box;
        s["box"] = observer.box_section();
        if (log.box_log) s["box"]["recorded"] = recorded_box_state(log);
        s["wall_time_s"] =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        s["files"] = {{"firmware", "firmware.csv"}};
        write_json(dir / "summary.json", s);
        std::printf("replayed %zu frames: %llu periods, %zu alarm(s)\n", log.records.size(),
                    static_cast<unsigned long long>(r.periods), box["alarms"].size());
        if (log.box_log) {
            std::printf("the box's outputs: %llu recorded frames compared, %llu differ%s%s\n",
                        static_cast<unsigned long long>(r.compared_frames),
                        static_cast<unsigned long long>(r.differing_frames),
                        r.first_difference.empty() ? "" : "; first: ", r.first_difference.c_str());
            if (r.tracker_periods > 0)
                std::printf(
                    "%llu periods fused the box's EM tracker, whose samples a CAN log does "
                    "not hold: only their Alarms frames were compared (%llu frames not)\n",
                    static_cast<unsigned long long>(r.tracker_periods),
                    static_cast<unsigned long long>(r.uncomparable_frames));
            if (r.alarms_without_self_lock > 0)
                std::printf(
                    "from the first of them on, %llu Alarms frames were compared without their "
                    "self-lock fields (the loop alarm's gate reads the tracker's tip)\n",
                    static_cast<unsigned long long>(r.alarms_without_self_lock));
        }
        print_box_faults(s["box"]);
        if (log.box_log) {
            const Json& recorded = s["box"]["recorded"];
            for (const auto& [name, first] : recorded["fault_first_s"].items())
                std::printf(
                    "  %8.3f s  %-31s first set; in %llu of %llu recorded BoxStatus "
                    "frames\n",
                    first.get<double>(), ("recorded box fault " + name).c_str(),
                    static_cast<unsigned long long>(
                        recorded["fault_frames"][name].get<std::uint64_t>()),
                    static_cast<unsigned long long>(
                        recorded["status_frames"].get<std::uint64_t>()));
        }
        std::printf("wrote %s, %s%s%s\n", (dir / "firmware.csv").string().c_str(),
                    (dir / "summary.json").string().c_str(), record ? ", the box log " : "",
                    options.record.c_str());
        return log.box_log && (r.differing_frames != 0 || r.compared_frames == 0) ? 1 : 0;
    } catch (const OutputError& e) {
        std::cerr << "scopekin replay: " << e.what() << "\n";
        return 3;
    }
}

}  // namespace

void add_replay_command(CLI::App& app) {
    auto options = std::make_shared<ReplayOptions>();
    CLI::App* cmd = app.add_subcommand(
        "replay",
        "Feed a candump log (candump -L / canplayer format) through the unmodified firmware and "
        "write DIR/firmware.csv (the box's outputs and fault bits per period) and DIR/summary.json "
        "(alarms, the box's faults and counters, e.g. counter_gaps; for a box log also the "
        "recorded BoxStatus bits and BoxCounters values). A log written by "
        "`scopekin-box --record` (it holds the box's own "
        "frames) is replayed "
        "period by period at the recorded times, and the replayed KineticEstimate, ContactSummary, "
        "Alarms, EstimateEvidence and StationForces frames are compared with the recorded ones "
        "(periods that fused the box's EM tracker, EstimateEvidence.TipFromTracker, and the 10 "
        "after them compare only their Alarms frames, and from the first of them on without the "
        "self-lock fields: a CAN log does not hold the tracker's samples); a "
        "log of the handle sensors "
        "alone is run with a "
        "period every 5 ms. Exit status 0 done (and, for a box log, identical), 1 a box log "
        "replays to different "
        "outputs, 2 invalid log (the line is named), 3 an output cannot be written. The log must "
        "be in time order (equal time stamps are fine) with no gap between two lines longer than "
        "--max-gap-s. Only the frames the box's receive filter passes (the handle sensors' 0x110 "
        "and 0x111, and error frames) reach the box, as the kernel filters them for "
        "scopekin-box; summary.json counts the rest as frames_filtered.");
    cmd->add_option("log", options->log, "candump log file")->required()->check(CLI::ExistingFile);
    cmd->add_option("--out", options->out,
                    "Output directory (created if missing; old outputs in it are replaced)")
        ->required();
    cmd->add_option("--max-gap-s", options->max_gap_s,
                    "Longest time between two lines of the log, in seconds: a longer gap is "
                    "refused naming the line (a sensor log runs the box every 5 ms across it)")
        ->check(kGapSeconds)
        ->capture_default_str();
    cmd->add_option("--record", options->record,
                    "Also write the replayed box's log: every frame it received and sent, in "
                    "candump format as `scopekin-box --record` writes it (a box log: "
                    "`scopekin display` shows it, `scopekin replay` replays it)");
    cmd->add_flag("--quiet", options->quiet, "No progress on stderr");
    cmd->callback([options]() { throw CLI::RuntimeError(run_replay(*options)); });
}

}  // namespace scopekin::cli
