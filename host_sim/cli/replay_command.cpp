#include "host_sim/cli/replay_command.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "host_sim/cli/cli_support.hpp"
#include "host_sim/replay/candump_replay.hpp"
#include "host_sim/simulator/box_observer.hpp"

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

struct ReplayOptions {
    std::string log;
    std::string out;
    double max_gap_s = 60.0;
    bool quiet = false;
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
        const host_sim::ReplayResult r = host_sim::replay_candump(
            log, [&](const host_sim::BoxPeriod& p) { observer.observe(p); });
        firmware_csv.finish(true);
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
            s["identical"] = r.differing_frames == 0 && r.compared_frames > 0;
            s["first_difference"] = r.first_difference;
        }
        s["alarms"] = box["alarms"];
        s["firmware"] = box;
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
        }
        std::printf("wrote %s, %s\n", (dir / "firmware.csv").string().c_str(),
                    (dir / "summary.json").string().c_str());
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
        "write DIR/firmware.csv "
        "and DIR/summary.json. A log written by `scopekin-box --record` (it holds the box's own "
        "frames) is replayed "
        "period by period at the recorded times, and the replayed KineticEstimate, ContactSummary, "
        "Alarms and "
        "StationForces frames are compared with the recorded ones; a log of the handle sensors "
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
    cmd->add_flag("--quiet", options->quiet, "No progress on stderr");
    cmd->callback([options]() { throw CLI::RuntimeError(run_replay(*options)); });
}

}  // namespace scopekin::cli
