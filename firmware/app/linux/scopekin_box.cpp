// scopekin-box — the sensor box's program on a Linux box (x86-64 or aarch64): SocketCAN for the
// handle sensors and the outputs, optionally a serial port for the test bench's EM tracker, the
// firmware's cyclic executive at a fixed period.
//
//   scopekin-box --can IFACE [--serial DEV] [--period-ms N] [--record FILE] ...  (--help)
//
// This file is `main` for Linux: it parses the command line (CLI11, so this one translation unit
// is compiled with exceptions), picks the backends (SocketCAN, POSIX serial, Linux clock, the
// candump recorder) and runs firmware/executive's SensorBox, which sees only the HAL interfaces.
// SIGINT / SIGTERM stop the loop at the end of the current period; the record is flushed, a
// summary printed (and written as JSON with --stats) and the exit status says how it went:
//   0 stopped by a signal or --duration-s, 2 bad usage or a device that cannot be opened,
//   3 an I/O error while running (the record could not be written).
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "executive/sensor_box.hpp"
#include "hal/clock.hpp"
#include "hal/linux/linux_clock.hpp"
#include "hal/linux/recording_can_bus.hpp"
#include "hal/posix_serial/posix_serial_port.hpp"
#include "hal/socketcan/socketcan_bus.hpp"
#include "kinetics/default_reduced_tables.hpp"
#include "protocol/can/scopekin_messages.hpp"

namespace {

std::atomic<bool> stop_requested{false};
std::atomic<int> stop_signal{0};

extern "C" void on_stop_signal(int signal_number) {
    stop_signal.store(signal_number);
    stop_requested.store(true);
}

struct Options {
    std::string can_interface;
    std::string serial_device;
    std::uint32_t baud{115200};
    std::uint32_t period_ms{5};
    std::string record_path;
    double duration_s{0.0};
    std::uint32_t stale_periods{3};
    std::string stats_path;
    bool quiet{false};
};

/// The box's objects: large (kinetics state, drivers), so they live here once, not on the stack.
struct Box {
    scopekin::hal::LinuxMonotonicClock clock{};
    scopekin::hal::SocketCanBus can{};
    std::unique_ptr<scopekin::hal::RecordingCanBus> recorder{};
    scopekin::hal::PosixSerialPort serial{};
    scopekin::executive::SensorBox box{};
};

const char* state_name(scopekin::protocol::BoxState state) {
    switch (state) {
        case scopekin::protocol::BoxState::starting: return "starting";
        case scopekin::protocol::BoxState::running: return "running";
        case scopekin::protocol::BoxState::degraded: return "degraded";
        case scopekin::protocol::BoxState::no_estimate: return "no_estimate";
    }
    return "unknown";
}

nlohmann::json stats_json(const Box& box, double elapsed_s, std::uint64_t record_lines,
                          std::uint64_t record_errors, int signal_number) {
    const auto& counters = box.box.counters();
    const auto can = box.box.can_counters();
    const auto& handle = box.box.handle_sensors().counters();
    const auto& outputs = box.box.outputs();
    nlohmann::json json;
    json["elapsed_s"] = elapsed_s;
    json["stopped_by_signal"] = signal_number;
    json["periods"] = counters.periods;
    json["period_overruns"] = counters.period_overruns;
    json["box_state"] = state_name(box.box.box_state());
    json["can"] = {{"received", can.received},
                   {"sent", can.sent},
                   {"dropped", can.dropped},
                   {"send_failures", can.send_failures},
                   {"error_frames", can.error_frames},
                   {"bus_off_events", can.bus_off_events},
                   {"backend_errors", can.backend_errors}};
    json["box"] = {{"frames_read", counters.frames_read},
                   {"unknown_ids", counters.unknown_ids},
                   {"frames_published", counters.frames_published},
                   {"send_failures", counters.send_failures},
                   {"can_error_frames", box.box.can_health().error_frames()},
                   {"can_bus_off_events", box.box.can_health().bus_off_events()},
                   {"can_recoveries", box.box.can_health().recoveries()}};
    json["handle_sensors"] = {{"force_torque_samples", handle.force_torque_samples},
                              {"insertion_roll_samples", handle.insertion_roll_samples},
                              {"bad_length", handle.bad_length},
                              {"out_of_range", handle.out_of_range},
                              {"sensor_status", handle.sensor_status},
                              {"counter_gaps", handle.counter_gaps},
                              {"stale_events", handle.stale_events}};
    json["last_output"] = {
        {"step_index", outputs.step_index},
        {"tip_path_mm", static_cast<double>(outputs.tip_path_mm.raw()) / 65536.0},
        {"fault_flags", outputs.fault_flags},
        {"self_lock_alarm", outputs.self_lock_alarm}};
    json["record"] = {{"lines", record_lines}, {"write_errors", record_errors}};
    return json;
}

}  // namespace

int main(int argc, char** argv) {
    Options options;
    CLI::App app{
        "scopekin-box - the colonoscope sensor box on Linux: reads the handle sensors on CAN "
        "(and the test bench's EM tracker on a serial port), runs the fixed-point kinetic "
        "estimator every period and publishes the estimate, contact forces and alarms on CAN "
        "(messages: firmware/protocol/scopekin.dbc). Stops cleanly on SIGINT/SIGTERM.\n"
        "Exit status: 0 stopped, 2 bad usage or a device that cannot be opened, 3 I/O error."};
    app.add_option("--can", options.can_interface, "SocketCAN interface (e.g. can0, vcan0)")
        ->required();
    app.add_option("--serial", options.serial_device,
                   "serial device of the EM tracker / tip force sensor (e.g. /dev/ttyUSB0)");
    app.add_option("--baud", options.baud, "serial line rate, bit/s")->capture_default_str();
    app.add_option("--period-ms", options.period_ms, "period of the cyclic executive, ms")
        ->check(CLI::Range(1, 1000))
        ->capture_default_str();
    app.add_option("--record", options.record_path,
                   "record all CAN traffic (received and sent) to FILE in candump log format");
    app.add_option("--duration-s", options.duration_s,
                   "stop after this many seconds (0: run until a signal)")
        ->check(CLI::Range(0.0, 1.0e7))
        ->capture_default_str();
    app.add_option("--stale-periods", options.stale_periods,
                   "a handle sensor is stale after this many periods without a valid sample")
        ->check(CLI::Range(1, 1000))
        ->capture_default_str();
    app.add_option("--stats", options.stats_path, "write the final counters as JSON to FILE");
    app.add_flag("--quiet", options.quiet, "no progress line (once a second) on stderr");
    app.set_version_flag("--version", "scopekin-box 0.1.0");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    }

    static Box box;
    std::string error;
    static constexpr std::uint32_t kInputIds[] = {scopekin::protocol::kHandleForceTorqueId,
                                                  scopekin::protocol::kInsertionRollId};
    scopekin::hal::SocketCanConfig can_config;
    can_config.interface = options.can_interface;
    can_config.receive_ids = kInputIds;
    can_config.receive_buffer_bytes = 1 << 20;  // ~1500 frames: 0.7 s of both sensors at 1 kHz
    if (!box.can.open(can_config, error)) {
        std::fprintf(stderr, "scopekin-box: %s\n", error.c_str());
        return 2;
    }
    scopekin::hal::CanBus* bus = &box.can;
    if (!options.record_path.empty()) {
        box.recorder = std::make_unique<scopekin::hal::RecordingCanBus>(box.can, box.clock);
        if (!box.recorder->open(options.record_path, options.can_interface, error)) {
            std::fprintf(stderr, "scopekin-box: %s\n", error.c_str());
            return 2;
        }
        bus = box.recorder.get();
    }
    scopekin::hal::SerialPort* serial = nullptr;
    if (!options.serial_device.empty()) {
        char serial_error[256] = {};
        if (!box.serial.open(options.serial_device.c_str(), options.baud, serial_error)) {
            std::fprintf(stderr, "scopekin-box: %s\n", serial_error);
            return 2;
        }
        serial = &box.serial;
    }

    scopekin::executive::BoxConfig config;
    config.period_us = options.period_ms * 1000U;
    config.kinetics.tables = &scopekin::kinetics::default_reduced_tables();
    config.handle_sensors.stale_after_us = options.stale_periods * config.period_us;
    if (!box.box.init(config, *bus, serial)) {
        std::fprintf(stderr,
                     "scopekin-box: the estimator refused its configuration: running without "
                     "an estimate (BoxState no_estimate)\n");
    }

    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);

    if (!options.quiet) {
        std::fprintf(stderr, "scopekin-box: running on %s every %u ms%s%s%s%s\n",
                     options.can_interface.c_str(), options.period_ms,
                     serial != nullptr ? ", serial " : "", options.serial_device.c_str(),
                     options.record_path.empty() ? "" : ", recording to ",
                     options.record_path.c_str());
    }
    const std::uint64_t start_us = box.clock.now_us();
    const auto duration_us = static_cast<std::uint64_t>(options.duration_s * 1.0e6);
    scopekin::hal::PeriodicTimer timer(box.clock, config.period_us);
    std::uint64_t next_progress_us = start_us + 1000000U;
    while (!stop_requested.load()) {
        const std::uint64_t release_us = timer.wait_next();
        if (stop_requested.load()) {
            break;
        }
        const std::uint64_t now_us = box.clock.now_us();
        if (box.recorder) {
            box.recorder->set_send_time_us(now_us);  // replay runs the period at this time
        }
        box.box.run_period(now_us, timer.overruns());
        if (duration_us > 0U && release_us - start_us >= duration_us) {
            break;
        }
        if (!options.quiet && release_us >= next_progress_us) {
            next_progress_us += 1000000U;
            const auto& outputs = box.box.outputs();
            const auto can = box.box.can_counters();
            std::fprintf(
                stderr,
                "scopekin-box: t=%.0f s periods=%u received=%u dropped=%u sent=%u "
                "state=%s tip=%.1f mm faults=0x%04x/0x%04x self_lock=%d\n",
                static_cast<double>(release_us - start_us) / 1.0e6, box.box.counters().periods,
                can.received, can.dropped, can.sent, state_name(box.box.box_state()),
                static_cast<double>(outputs.tip_path_mm.raw()) / 65536.0,
                static_cast<unsigned>(outputs.fault_flags),
                static_cast<unsigned>(box.box.box_faults()), outputs.self_lock_alarm ? 1 : 0);
        }
    }
    const double elapsed_s = static_cast<double>(box.clock.now_us() - start_us) / 1.0e6;

    bool io_ok = true;
    std::uint64_t record_lines = 0;
    std::uint64_t record_errors = 0;
    if (box.recorder) {
        io_ok = box.recorder->close();
        record_lines = box.recorder->lines_written();
        record_errors = box.recorder->write_errors();
        if (!io_ok) {
            std::fprintf(stderr, "scopekin-box: %llu CAN record lines could not be written to %s\n",
                         static_cast<unsigned long long>(record_errors),
                         options.record_path.c_str());
        }
    }
    const nlohmann::json stats =
        stats_json(box, elapsed_s, record_lines, record_errors, stop_signal.load());
    if (!options.stats_path.empty()) {
        std::ofstream out(options.stats_path);
        out << stats.dump(2) << "\n";
        if (!out) {
            std::fprintf(stderr, "scopekin-box: cannot write %s\n", options.stats_path.c_str());
            io_ok = false;
        }
    }
    if (!options.quiet) {
        std::fprintf(stderr, "scopekin-box: stopped after %.1f s: %s\n", elapsed_s,
                     stats.dump().c_str());
    }
    return io_ok ? 0 : 3;
}
