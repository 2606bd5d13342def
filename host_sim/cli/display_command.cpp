#include "host_sim/cli/display_command.hpp"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

#include "hal/socketcan/socketcan_bus.hpp"
#include "host_sim/cli/cli_support.hpp"
#include "host_sim/cli/view_command.hpp"
#include "host_sim/replay/candump_replay.hpp"
#include "host_sim/view/box_bus_rows.hpp"
#include "host_sim/view/live_view.hpp"
#include "host_sim/view/view_server.hpp"

namespace scopekin::cli {
namespace {

struct DisplayOptions {
    std::string log;
    std::string can_interface;
    double pace = 1.0;
    double max_gap_s = 60.0;
    std::uint16_t port = 8765;
    bool no_browser = false;
    bool quiet = false;
};

/// A page opened during a live session gets its last 10 minutes (25 messages per second).
constexpr std::size_t kLiveHistoryMessages = 15'000;
/// How long one receive waits, µs: the stop signal is seen within this.
constexpr std::uint32_t kReceiveTimeout_us = 100'000;

std::unique_ptr<view::LiveView> open_display(const DisplayOptions& options,
                                             const std::string& source) {
    auto live_view = std::make_unique<view::LiveView>(
        view::box_page_data("the box: " + source,
                            "the box's display: what the box sends on the CAN bus (its tip along "
                            "its model's colon, its uncertainty, stations and alarms) and the "
                            "handle sensors' frames, from " +
                                source),
        options.port);
    std::printf("scopekin display: the box's view at %s\n", live_view->url().c_str());
    std::fflush(stdout);
    if (!options.no_browser) view::open_in_browser(live_view->url());
    return live_view;
}

/// The page's step for one period's row (the box's page has no shapes).
host_sim::LiveViewStep display_step(double time_s, const nlohmann::ordered_json& row) {
    return {time_s, [&row] { return row; }, [] { return std::string(); }};
}

void print_heard(const char* what, const view::BoxBusRows& rows) {
    std::printf(
        "scopekin display: %s %llu box periods (%llu frames refused, %llu not the box's "
        "or the handle's)\n",
        what, static_cast<unsigned long long>(rows.periods()),
        static_cast<unsigned long long>(rows.refused()),
        static_cast<unsigned long long>(rows.ignored()));
}

int display_log(const DisplayOptions& options) {
    host_sim::CandumpLog log;
    try {
        host_sim::CandumpReadOptions read_options;
        read_options.max_gap_us = static_cast<std::uint64_t>(options.max_gap_s * 1e6);
        log = host_sim::read_candump_log(options.log, read_options);
    } catch (const host_sim::CandumpLineError& e) {
        std::cerr << "scopekin display: invalid log: " << e.what() << "\n";
        return 2;
    }
    if (!log.box_log) {
        std::cerr << "scopekin display: " << options.log
                  << ": no frame of the box (KineticEstimate, 0x181): a log of the handle "
                     "sensors alone; `scopekin replay LOG --out DIR --record box.log` writes the "
                     "box's\n";
        return 2;
    }
    std::unique_ptr<view::LiveView> live_view;
    try {
        live_view = open_display(options, options.log);
    } catch (const std::runtime_error& e) {  // ViewServerError, ViewAssetsError
        std::cerr << "scopekin display: " << e.what() << "\n";
        return 2;
    }
    view::BoxBusRows rows([&](double t, const nlohmann::ordered_json& row) {
        live_view->step(display_step(t, row));
    });
    const auto wall_start = std::chrono::steady_clock::now();
    const std::uint64_t first_us = log.records.front().timestamp_us;
    const double end_s = static_cast<double>(log.records.back().timestamp_us - first_us) * 1e-6;
    ProgressBar bar(options.quiet);
    for (std::size_t i = 0; i < log.records.size(); ++i) {
        const hal::CandumpRecord& r = log.records[i];
        const double t = static_cast<double>(r.timestamp_us - first_us) * 1e-6;
        keep_pace(static_cast<std::int64_t>(r.timestamp_us), static_cast<std::int64_t>(first_us),
                  options.pace, wall_start);
        rows.feed(r.timestamp_us, r.frame);
        if (i % 2000 == 0 && end_s > 0) {
            char text[64];
            std::snprintf(text, sizeof text, "%.1f of %.1f s", t, end_s);
            bar.update(t / end_s, text);
        }
    }
    rows.flush();
    bar.done();
    print_heard("showed", rows);
    live_view->serve_box_page_until_stopped("scopekin display");
    return 0;
}

int display_bus(const DisplayOptions& options) {
    hal::SocketCanBus bus;
    hal::SocketCanConfig config;
    config.interface = options.can_interface;  // every frame: the box's and the handle's
    std::string error;
    if (!bus.open(config, error)) {
        std::cerr << "scopekin display: --can " << options.can_interface << ": " << error << "\n";
        return 2;
    }
    std::unique_ptr<view::LiveView> live_view;
    try {
        live_view = open_display(options, options.can_interface);
    } catch (const std::runtime_error& e) {
        std::cerr << "scopekin display: " << e.what() << "\n";
        return 2;
    }
    live_view->keep_last(kLiveHistoryMessages);
    // Ctrl-C ends the session (exit 0): the bus has no end of its own.
    std::atomic<bool> stop{false};
    std::thread stopper([&] {
        live_view->wait_for_stop_signal();
        stop = true;
    });
    view::BoxBusRows rows([&](double t, const nlohmann::ordered_json& row) {
        live_view->step(display_step(t, row));
    });
    auto last_report = std::chrono::steady_clock::now();
    int status = 0;
    while (!stop.load()) {
        hal::ReceivedCanFrame received{};
        const hal::CanStatus s = bus.receive(received, kReceiveTimeout_us);
        if (s == hal::CanStatus::ok) {
            rows.feed(received.timestamp_us, received.frame);
        } else if (s != hal::CanStatus::timeout && s != hal::CanStatus::bus_off) {
            std::cerr << "scopekin display: --can " << options.can_interface
                      << ": the bus failed while reading\n";
            status = 3;
            break;
        }
        const auto now = std::chrono::steady_clock::now();
        if (!options.quiet && now - last_report > std::chrono::seconds(10)) {
            last_report = now;
            std::fprintf(stderr, "scopekin display: %llu box periods heard\n",
                         static_cast<unsigned long long>(rows.periods()));
        }
    }
    rows.flush();
    print_heard("heard", rows);
    if (status != 0) kill(getpid(), SIGTERM);  // the stopper waits for the signal thread's
    stopper.join();
    return status;
}

}  // namespace

void add_display_command(CLI::App& app) {
    auto options = std::make_shared<DisplayOptions>();
    CLI::App* cmd = app.add_subcommand(
        "display",
        "The box's display in a browser: only what the box sends on the CAN bus (its tip along "
        "its model's colon with one SD, its stations and their forces, the largest contact force, "
        "the loop and contact-force alarms, its fault flags) and the handle sensors' frames on "
        "the same bus, as `scopekin run --view` shows them; no truth. Live from a SocketCAN "
        "interface beside a running `scopekin-box` (--can; until Ctrl-C, a page opened later gets "
        "the last 10 minutes), or from a box log (`scopekin-box --record`, `candump -L`, "
        "`scopekin replay --record`) at --pace; the page stays served until Ctrl-C. Serves on "
        "127.0.0.1 and prints the address. Exit status 0 done, 2 invalid input (a log that is "
        "not the box's, an interface that cannot be opened, the port in use), 3 the bus failed "
        "while reading.");
    CLI::Option* log = cmd->add_option("log", options->log, "A box log (candump format)")
                           ->check(CLI::ExistingFile);
    CLI::Option* can = cmd->add_option("--can", options->can_interface,
                                       "Listen on this SocketCAN interface (e.g. can0, vcan0)");
    log->excludes(can);
    cmd->add_option("--pace", options->pace,
                    "With a log: recorded seconds per wall second (1: as the box lived it; 0: "
                    "as fast as it goes)")
        ->default_val(1.0)
        ->check(CLI::Range(0.0, 1000.0))
        ->needs(log);
    cmd->add_option("--max-gap-s", options->max_gap_s,
                    "With a log: the longest time between two lines, s (as `scopekin replay`)")
        ->default_val(60.0)
        ->check(CLI::Range(1e-3, host_sim::kMaxGapLimit_s))
        ->needs(log);
    cmd->add_option("--port", options->port, "The port on 127.0.0.1 (0: any free one)")
        ->default_val(8765)
        ->check(CLI::Range(0, 65535));
    cmd->add_flag("--no-browser", options->no_browser, "Do not ask the desktop to open a browser");
    cmd->add_flag("--quiet", options->quiet, "No progress on stderr");
    cmd->callback([options, log, can]() {
        if (log->count() == 0 && can->count() == 0)
            throw CLI::ValidationError("display", "give a box log or --can IFACE");
        throw CLI::RuntimeError(options->log.empty() ? display_bus(*options)
                                                     : display_log(*options));
    });
}

}  // namespace scopekin::cli
