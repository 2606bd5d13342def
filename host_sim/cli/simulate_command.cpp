#include "host_sim/cli/simulate_command.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <system_error>

#include "host_sim/cli/cli_support.hpp"
#include "host_sim/cli/live_run.hpp"
#include "host_sim/cli/view_command.hpp"
#include "host_sim/simulator/world_readout.hpp"
#include "host_sim/view/live_view.hpp"
#include "host_sim/view/view_data.hpp"
#include "host_sim/view/view_page.hpp"
#include "model/scenario/scenario.hpp"
#include "model/scenario/simulation.hpp"

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

/// The keys every summary.json starts with.
std::string num(double v) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.7g", v);
    return buffer;
}

Json summary_header(const model::Scenario& sc, const char* kind, bool complete,
                    const std::string& message) {
    Json summary;
    summary["scenario"] = sc.source;
    summary["kind"] = kind;
    summary["description"] = sc.description;
    summary["status"] = complete ? "complete" : "failed";
    summary["message"] = message;
    return summary;
}

/// The run's lines on stdout and stderr; returns the exit status (0 complete, 1 failed).
int report_world(const LiveRunReport& report, const SimulateOptions& options) {
    const Json& s = report.summary;
    const fs::path dir(options.out);
    for (const auto& w : s["warnings"])
        std::cerr << "scopekin simulate: warning: " << w.get<std::string>() << "\n";
    if (!report.complete) {
        std::cerr << "scopekin simulate: failed: " << s["message"].get<std::string>() << "\n"
                  << "wrote the files up to the failure into " << dir.string()
                  << " (summary.json says what)\n";
        return 1;
    }
    std::printf(
        "complete: %.3f s simulated, %.1f s wall time (%.2fx real time); peak handle force %.2f N, "
        "%zu alarm(s) from the box\n",
        s["duration_s"].get<double>(), s["wall_time_s"].get<double>(),
        s["real_time_factor"].get<double>(), s["peak_handle_force_N"]["true"].get<double>(),
        s["alarms"].size());
    const Json& procedure = s["procedure"];
    if (procedure["kind"] == "physician")
        std::printf(
            "physician %s (seed %s): %s, %zu loop reduction(s)%s\n",
            procedure["style"].get<std::string>().c_str(), procedure["seed"].dump().c_str(),
            procedure["end_reason"].get<std::string>().c_str(),
            procedure["loop_reductions"].get<std::size_t>(),
            procedure["cecum_reached"].get<bool>()
                ? (", cecum at " + num(procedure["cecum_time_s"].get<double>()) + " s with " +
                   num(procedure["insertion_at_cecum_mm"].get<double>()) + " mm inserted")
                      .c_str()
                : "");
    std::printf(
        "wrote recording.csv, world.csv, firmware.csv, truth.csv, procedure.csv, %ssnapshots.json, "
        "summary.json into %s\n",
        options.frames_hz > 0 || options.view ? "frames.jsonl, " : "", dir.string().c_str());
    return 0;
}

/// The live view once the run has ended: the page becomes the run's replay (if it can be read),
/// served until Ctrl-C.
void finish_live_view(view::LiveView& live_view, const fs::path& dir) {
    std::string replay;
    try {
        replay = view::render_view_page(view::read_run_view(dir), view::view_assets_folder());
    } catch (const view::ViewDataError& e) {
        std::cerr << "scopekin simulate: the view keeps the live page: " << e.what() << "\n";
    }
    live_view.finish(replay);
    std::printf(
        "scopekin simulate: %s at %s (%zu live messages sent; reload for the replay; "
        "Ctrl-C to stop)\n",
        replay.empty() ? "the live view stays" : "the run's replay is", live_view.url().c_str(),
        live_view.messages());
    std::fflush(stdout);
    live_view.wait_for_stop_signal();
}

int run_world(const model::Scenario& sc, const SimulateOptions& options) {
    std::unique_ptr<view::LiveView> live_view;
    if (options.view) {
        try {
            live_view = std::make_unique<view::LiveView>(
                view::live_page_data(
                    nlohmann::json::parse(host_sim::WorldReader::colon_json(*sc.colon).dump()),
                    sc.scope.elements + 1, fs::path(options.out).filename().string(),
                    sc.description + " · live", false),
                options.port);
        } catch (const view::ViewServerError& e) {
            std::cerr << "scopekin simulate: --view: " << e.what() << "\n";
            return 2;
        } catch (const view::ViewAssetsError& e) {
            std::cerr << "scopekin simulate: --view: " << e.what() << "\n";
            return 2;
        }
        std::printf("scopekin simulate: live view at %s\n", live_view->url().c_str());
        std::fflush(stdout);
        if (!options.no_browser) view::open_in_browser(live_view->url());
    }
    LiveRunOptions live;
    live.out = options.out;
    live.seed = options.seed;
    live.quiet = options.quiet;
    // The live view's replay wants the shapes over time: --view writes them at 10 Hz by default.
    live.frames_hz = options.view && options.frames_hz == 0 ? 10.0 : options.frames_hz;
    if (live_view)
        live.view_step = [&live_view](const host_sim::LiveViewStep& step) {
            live_view->step(step);
        };
    const LiveRunReport report = run_live_to_folder(sc, live);
    const int status = report_world(report, options);
    if (live_view) finish_live_view(*live_view, options.out);
    return status;
}

int run_free_beam(model::Scenario& sc, const SimulateOptions& options) {
    model::io::BeamProblem& p = *sc.beam_problem;
    const fs::path dir(options.out);
    prepare_directory(dir, {"summary.json", "recording.csv", "recording.incomplete.csv"});
    PartFile recording(dir / "recording.csv", dir / "recording.incomplete.csv");
    if (!options.quiet)
        std::cerr << "solving the free beam " << sc.source
                  << " statically: " << p.beam.element_count() << " elements, "
                  << p.settings.load_steps << " load steps ..." << std::endl;
    const auto start = std::chrono::steady_clock::now();
    const model::StaticReport report = model::solve_static(p.beam, p.loads, p.supports, p.settings);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    recording.stream() << "node,x_mm,y_mm,z_mm\n";
    for (std::size_t node : p.output_nodes) {
        const Eigen::Vector3d x = p.beam.position(node);
        recording.stream() << node << ',' << num(x.x()) << ',' << num(x.y()) << ',' << num(x.z())
                           << '\n';
    }
    const fs::path recording_file = recording.finish(report.converged);
    std::size_t accepted = 0;
    for (const auto& s : report.steps)
        accepted += s.converged ? 1 : 0;
    Json summary = summary_header(sc, "free_beam", report.converged, report.message);
    summary["converged"] = report.converged;
    summary["newton_iterations"] = report.total_iterations;
    summary["load_steps_accepted"] = accepted;
    summary["load_steps_attempted"] = report.steps.size();
    summary["wall_time_s"] = wall;
    summary["output_nodes"] = p.output_nodes;
    summary["files"] = Json{{"recording", recording_file.filename().string()}};
    write_json(dir / "summary.json", summary);
    if (!report.converged) {
        std::cerr << "scopekin simulate: failed: the static solve did not converge: "
                  << report.message << "\n";
        return 1;
    }
    std::printf("complete: converged after %d Newton iterations in %.3f s\nwrote %s, %s\n",
                report.total_iterations, wall, recording_file.string().c_str(),
                (dir / "summary.json").string().c_str());
    return 0;
}

}  // namespace

int run_simulate(const SimulateOptions& options) {
    model::Scenario sc = model::read_scenario_file(options.scenario);  // ModelError: exit 2
    try {
        if (sc.kind == model::ScenarioKind::free_beam && options.view) {
            std::cerr << "scopekin simulate: --view needs a world scenario (" << options.scenario
                      << " is a free beam, solved statically)\n";
            return 2;
        }
        return sc.kind == model::ScenarioKind::free_beam ? run_free_beam(sc, options)
                                                         : run_world(sc, options);
    } catch (const OutputError& e) {
        std::cerr << "scopekin simulate: " << e.what() << "\n";
        return 3;
    }
}

void add_simulate_command(CLI::App& app) {
    auto options = std::make_shared<SimulateOptions>();
    CLI::App* cmd = app.add_subcommand(
        "simulate",
        "Run a scenario file (schema in model/scenario/README.md). A world scenario is simulated "
        "live: the scope in "
        "the colon driven by the procedure (\"procedure\": scripted, or \"physician\": hands "
        "that react to the world, model/physician/README.md; with the scenario's truth effects), "
        "read by the sensor models every 1 ms, "
        "and the unmodified firmware fed with what they deliver every 5 ms. Writes "
        "DIR/recording.csv (what the "
        "sensors delivered, host_sim/recording/RECORDING.md), DIR/world.csv (the true state at "
        "outputs.sample_rate_Hz), "
        "DIR/firmware.csv (the box's outputs and fault bits per period), DIR/truth.csv (what the "
        "box "
        "estimates, true, at the same periods: host_sim/README.md, model/truth/README.md; its "
        "episodes in the summary's \"truth\"), DIR/procedure.csv (what the hand did, at "
        "world.csv's rows), DIR/snapshots.json and DIR/summary.json (its \"procedure\": how the "
        "procedure went, the cecum reached or not). "
        "A free beam "
        "scenario is solved statically: DIR/recording.csv has one row per output node. While "
        "running, CSV files "
        "are NAME.part; a run that fails leaves NAME.incomplete.csv and a summary with status "
        "\"failed\". Exit "
        "status 0 complete, 1 the run failed (a step or the contact solver did not converge, or "
        "the state became "
        "unphysical), 2 invalid scenario (nothing written), 3 an output cannot be written.");
    cmd->add_option("scenario", options->scenario, "Scenario JSON file")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--out", options->out,
                    "Output directory (created if missing; old outputs in it are replaced)")
        ->required();
    cmd->add_option("--seed", options->seed,
                    "Seed of the sensor models' noise and dropouts (same seed, same run; 0 .. "
                    "2^64-1)")
        ->default_val(1)
        ->check(whole_number());
    cmd->add_option("--frames", options->frames_hz,
                    "World scenarios: also write DIR/frames.jsonl, the scope's and the colon's "
                    "shapes and the contact forces this many times per simulated second (0 .. "
                    "100; 0, the default: none), which `scopekin view DIR` replays in 3D")
        ->default_val(0)
        ->check(CLI::Range(0.0, 100.0));
    add_live_view_options(
        cmd, options->view, options->port, options->no_browser,
        "World scenarios: stream the run to the browser view while it runs (`scopekin view`'s "
        "page, live: at most 25 updates per second), then serve the run's replay there until "
        "Ctrl-C (with frames.jsonl at 10 Hz unless --frames says otherwise). Prints the address; "
        "exit status 2 if the port is in use");
    cmd->add_flag("--quiet", options->quiet, "No progress on stderr");
    cmd->callback([options]() { throw CLI::RuntimeError(run_simulate(*options)); });
}

}  // namespace scopekin::cli
