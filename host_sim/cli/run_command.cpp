#include "host_sim/cli/run_command.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "host_sim/cli/cli_support.hpp"
#include "host_sim/cli/live_run.hpp"
#include "host_sim/cli/view_command.hpp"
#include "host_sim/recording/recording_reader.hpp"
#include "host_sim/simulator/box_observer.hpp"
#include "host_sim/simulator/firmware_loop.hpp"
#include "host_sim/simulator/live_simulation.hpp"
#include "host_sim/view/live_view.hpp"
#include "host_sim/view/view_page.hpp"
#include "host_sim/view/view_server.hpp"

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

/// The box's page (`run --view`).
std::unique_ptr<view::LiveView> open_box_view(const RunOptions& options) {
    auto live_view = std::make_unique<view::LiveView>(
        view::box_page_data("the box: " + fs::path(options.recording).filename().string(),
                            "what the box knows (no truth): its tip along its model's colon, its "
                            "uncertainty, its stations and alarms, from " +
                                options.recording),
        options.port);
    std::printf("scopekin run: the box's view at %s\n", live_view->url().c_str());
    std::fflush(stdout);
    if (!options.no_browser) view::open_in_browser(live_view->url());
    return live_view;
}

}  // namespace

int run_recording(const RunOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    recording::RecordingReaderOptions reader_options;
    reader_options.gap_threshold_s = options.gap_threshold_s;
    reader_options.max_gap_s = options.max_gap_s;
    recording::Recording rec;
    try {
        rec = recording::RecordingReader(reader_options).read_file(options.recording);
    } catch (const recording::RecordingError& e) {
        std::cerr << "scopekin run: invalid recording: " << e.what() << "\n";
        return 2;
    }
    if (rec.rows.empty()) {
        std::cerr << "scopekin run: invalid recording: " << options.recording
                  << ": no rows after the header\n";
        return 2;
    }
    std::unique_ptr<view::LiveView> live_view;
    if (options.view) {
        try {
            live_view = open_box_view(options);
        } catch (const view::ViewServerError& e) {
            std::cerr << "scopekin run: --view: " << e.what() << "\n";
            return 2;
        } catch (const view::ViewAssetsError& e) {
            std::cerr << "scopekin run: --view: " << e.what() << "\n";
            return 2;
        }
    }
    try {
        const fs::path dir(options.out);
        prepare_directory(dir, {"summary.json", "firmware.csv", "firmware.incomplete.csv"});
        PartFile firmware_csv(dir / "firmware.csv", dir / "firmware.incomplete.csv");
        host_sim::BoxObserver observer(&firmware_csv.stream());
        host_sim::HandleReading handle;  // what the box last received (the page's handle rows)
        host_sim::FirmwareLoop loop([&](const host_sim::BoxPeriod& p) {
            observer.observe(p);
            if (live_view) {
                const double t = static_cast<double>(p.time_us) * 1e-6;
                live_view->step({t, [&] { return host_sim::box_view_row(t, handle, *p.outputs); },
                                 [] { return std::string(); }});
            }
        });
        const auto wall_start = std::chrono::steady_clock::now();
        ProgressBar bar(options.quiet);
        const double end_s = static_cast<double>(rec.rows.back().time_us) * 1e-6;
        for (std::size_t i = 0; i < rec.rows.size(); ++i) {
            if (live_view)
                keep_pace(rec.rows[i].time_us, rec.rows.front().time_us, options.pace, wall_start);
            if (rec.rows[i].handle) {
                handle.force_N = rec.rows[i].handle->force_N;
                handle.torque_Nmm = rec.rows[i].handle->torque_Nmm;
            }
            if (rec.rows[i].insertion_roll)
                handle.insertion_mm = rec.rows[i].insertion_roll->insertion_mm;
            loop.deliver(rec.rows[i]);
            if (i % 1000 == 0) {
                char text[64];
                std::snprintf(text, sizeof text, "t=%.1f/%.1f s",
                              static_cast<double>(rec.rows[i].time_us) * 1e-6, end_s);
                bar.update(static_cast<double>(i) / static_cast<double>(rec.rows.size()), text);
            }
        }
        loop.finish(static_cast<std::uint64_t>(rec.rows.back().time_us));
        bar.update(1.0, "done");
        bar.done();
        firmware_csv.finish(true);

        Json gaps = Json::array();
        for (const recording::RecordingGap& g : rec.gaps)
            gaps.push_back({{"signal", g.signal},
                            {"start_s", g.start_s},
                            {"end_s", g.end_s},
                            {"duration_s", g.duration_s()}});
        const Json box = observer.to_json();
        Json s;
        s["recording"] = options.recording;
        s["status"] = "complete";
        s["flagged"] = !rec.gaps.empty();
        s["gaps"] = gaps;
        s["rows"] = rec.rows.size();
        s["first_time_s"] = static_cast<double>(rec.rows.front().time_us) * 1e-6;
        s["last_time_s"] = end_s;
        s["periods"] = loop.periods();
        s["alarms"] = box["alarms"];
        s["firmware"] = box;
        s["box"] = observer.box_section();
        s["wall_time_s"] =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        s["files"] = {{"firmware", "firmware.csv"}};
        write_json(dir / "summary.json", s);
        for (const recording::RecordingGap& g : rec.gaps)
            std::cerr << "scopekin run: warning: gap in " << g.signal << " from " << g.start_s
                      << " s to " << g.end_s << " s (" << g.duration_s() * 1000.0
                      << " ms without a sample): the box held its last value and flagged it stale "
                         "(fault_flags in "
                         "firmware.csv; summary.json \"gaps\")\n";
        std::printf(
            "complete: %zu rows, %.3f s, %llu firmware periods, %zu alarm(s)%s\nwrote %s, %s\n",
            rec.rows.size(), end_s, static_cast<unsigned long long>(loop.periods()),
            box["alarms"].size(), rec.gaps.empty() ? "" : ", flagged: gaps in the handle signals",
            (dir / "firmware.csv").string().c_str(), (dir / "summary.json").string().c_str());
        print_box_faults(s["box"]);
        if (live_view) live_view->serve_box_page_until_stopped("scopekin run");
        return 0;
    } catch (const OutputError& e) {
        std::cerr << "scopekin run: " << e.what() << "\n";
        return 3;
    }
}

void add_run_command(CLI::App& app) {
    auto options = std::make_shared<RunOptions>();
    CLI::App* cmd = app.add_subcommand(
        "run",
        "Feed a recording (CSV, host_sim/recording/RECORDING.md; `scopekin simulate` writes one) "
        "through the unmodified "
        "firmware: its rows become the CAN frames and serial bytes the box receives, at their "
        "times; the box runs "
        "every 5 ms. Writes DIR/firmware.csv (the box's outputs and fault bits per period) and "
        "DIR/summary.json (alarms, gaps, the box's faults and counters). A "
        "malformed recording is refused with its line and column (exit 2); a gap in the handle "
        "signals is flagged, "
        "not refused. With --view the box's own page (`scopekin view`'s, live: only what the box "
        "knows, no truth) follows the recording at --pace. Exit status 0 done, 2 invalid "
        "recording (or --view's port in use), 3 an output cannot be written.");
    cmd->add_option("recording", options->recording, "Recording CSV file")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--out", options->out,
                    "Output directory (created if missing; old outputs in it are replaced)")
        ->required();
    cmd->add_option("--gap-s", options->gap_threshold_s,
                    "A handle signal silent longer than this [s] is a gap: flagged, not refused")
        ->default_val(0.05)
        ->check(positive_seconds());
    cmd->add_option("--max-gap-s", options->max_gap_s,
                    "Refuse a recording with two rows further apart than this [s] (the line is "
                    "named): the box would step a period every 5 ms across the gap")
        ->default_val(recording::kDefaultMaxGap_s)
        ->check(positive_seconds());
    CLI::Option* view_flag = add_live_view_options(
        cmd, options->view, options->port, options->no_browser,
        "The box's page in the browser while it runs: what a physician would glance at (the "
        "box's tip along its model's colon with its uncertainty, its stations, the alarms, the "
        "handle's force); then served until Ctrl-C. Prints the address");
    cmd->add_option("--pace", options->pace,
                    "With --view: recorded seconds per wall second (1: as the box lived it; 0: "
                    "as fast as it goes)")
        ->default_val(1.0)
        ->check(CLI::Range(0.0, 1000.0))
        ->needs(view_flag);
    cmd->add_flag("--quiet", options->quiet, "No progress on stderr");
    cmd->callback([options]() { throw CLI::RuntimeError(run_recording(*options)); });
}

}  // namespace scopekin::cli
