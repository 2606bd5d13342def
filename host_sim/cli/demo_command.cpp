#include "host_sim/cli/demo_command.hpp"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "host_sim/cli/cli_support.hpp"
#include "host_sim/cli/live_run.hpp"
#include "model/scenario/scenario.hpp"

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;

struct DemoOptions {
    std::string out;
    std::string scenario = SCOPEKIN_DEMO_SCENARIO;
    std::uint64_t seed = 1;
    bool quiet = false;
};

/// The demo's shapes for `scopekin view` (frames.jsonl): 10 per simulated second, about 1 MB per
/// 10 s of run.
constexpr double kDemoFrames_Hz = 10.0;

/// This program's path, for the command line the demo prints last.
std::string this_program() {
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    return ec ? std::string("scopekin") : self.string();
}

std::string default_folder() {
    const std::time_t now = std::time(nullptr);
    char name[64];
    std::strftime(name, sizeof name, "scopekin-demo-%Y%m%d-%H%M%S", std::localtime(&now));
    return name;
}

/// Draws the plots with the bundled script (python3-matplotlib), run with an argument vector
/// (no shell: the folder's name reaches it as it is). The summary is still summary.json.part.
ProgramResult draw_plots(const fs::path& dir, const fs::path& summary_part, bool quiet) {
    std::vector<std::string> argv{SCOPEKIN_PYTHON, SCOPEKIN_PLOT_SCRIPT};
    if (quiet) argv.emplace_back("--quiet");
    argv.emplace_back("--summary");
    argv.push_back(fs::absolute(summary_part).string());
    argv.push_back(fs::absolute(dir).string());  // absolute: a name starting with '-' is no option
    return run_program(argv);
}

int run_demo(const DemoOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    model::Scenario sc = model::read_scenario_file(options.scenario);  // ModelError: exit 2
    if (sc.kind != model::ScenarioKind::world) {
        std::cerr << "scopekin demo: " << options.scenario
                  << " is not a world scenario (no colon)\n";
        return 2;
    }
    const fs::path dir = options.out.empty() ? fs::path(default_folder()) : fs::path(options.out);
    std::printf("scopekin demo: %s\nwriting into %s\n", sc.description.c_str(),
                dir.string().c_str());
    std::fflush(stdout);
    try {
        LiveRunOptions live;
        live.out = dir;
        live.seed = options.seed;
        live.quiet = options.quiet;
        live.command = "demo";
        live.frames_hz = kDemoFrames_Hz;
        // The plots are drawn before summary.json is renamed (it is renamed last of all).
        std::optional<ProgramResult> plots;
        live.before_summary = [&](const fs::path& summary_part, bool complete) {
            if (!complete) return;  // the run failed: exit status 1, no plots
            if (!options.quiet) std::cerr << "drawing the plots ..." << std::endl;
            plots = draw_plots(dir, summary_part, options.quiet);
        };
        const LiveRunReport report = run_live_to_folder(sc, live);
        print_run_tables(report);
        if (!report.complete) {
            std::cerr << "scopekin demo: the simulation failed: "
                      << report.summary["message"].get<std::string>() << "\n";
            return 1;
        }
        if (!plots || !plots->ok()) {
            std::cerr << "scopekin demo: the plots could not be drawn (" << SCOPEKIN_PLOT_SCRIPT
                      << " " << (plots ? plots->describe() : "did not run")
                      << "; is python3-matplotlib installed? ./scopekin.sh installs it)\n";
            return 3;
        }
        const double wall =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf(
            "\nwrote into %s: recording.csv, world.csv, firmware.csv, truth.csv, frames.jsonl, "
            "snapshots.json, summary.json, forces.png, "
            "advance.png, snapshots.png (%.1f s in all)\n"
            "to see it in a browser (3D replay, the box's estimate beside the truth):\n  %s view "
            "%s\n",
            dir.string().c_str(), wall, this_program().c_str(), dir.string().c_str());
        return 0;
    } catch (const OutputError& e) {
        std::cerr << "scopekin demo: " << e.what() << "\n";
        return 3;
    }
}

}  // namespace

void add_demo_command(CLI::App& app) {
    auto options = std::make_shared<DemoOptions>();
    CLI::App* cmd = app.add_subcommand(
        "demo",
        "The main job: a simulated colonoscopy through the bundled default "
        "colon and the unmodified firmware "
        "(host_sim/scenarios/demo_n_loop.json): the tip locks at the "
        "sigmoid-descending junction, an N-shaped sigmoid "
        "loop forms, the box's self-lock alarm fires, the physician withdraws "
        "with clockwise torque to straighten "
        "it (the sigmoid pleats onto the scope) and advances again, steering the tip while the "
        "assistant presses on "
        "the abdomen, into the cecum. Prints "
        "the alarm timeline, the box's fault flags and a summary table; writes "
        "recording.csv, world.csv, firmware.csv, truth.csv, frames.jsonl (the shapes `scopekin "
        "view` replays, 10 per second), snapshots.json, summary.json "
        "and the plots forces.png, advance.png, "
        "snapshots.png, and prints the `scopekin view` command that shows the run in a browser. "
        "Exit status 0 done, 1 the simulation failed, 2 invalid "
        "scenario, 3 an output (or a plot) "
        "cannot be written.");
    cmd->add_option("--out", options->out,
                    "Output directory (default: a new folder scopekin-demo-YYYYMMDD-HHMMSS here; "
                    "its name is printed)");
    cmd->add_option("--scenario", options->scenario,
                    "Another world scenario to run instead of the bundled one")
        ->check(CLI::ExistingFile);
    cmd->add_option("--seed", options->seed,
                    "Seed of the sensor models' noise and dropouts (0 .. 2^64-1)")
        ->default_val(1)
        ->check(whole_number());
    cmd->add_flag("--quiet", options->quiet, "No progress on stderr");
    cmd->callback([options]() { throw CLI::RuntimeError(run_demo(*options)); });
}

}  // namespace scopekin::cli
