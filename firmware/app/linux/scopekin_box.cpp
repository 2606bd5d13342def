// scopekin-box — the sensor box's program on a Linux box (x86-64 or aarch64): SocketCAN for the
// handle sensors and the outputs, optionally a serial port for the test bench's EM tracker, the
// firmware's cyclic executive at a fixed period.
//
//   scopekin-box --can IFACE [--serial DEV] [--period-ms N] [--record FILE] [--view] ...  (--help)
//
// This file is `main` for Linux: it parses the command line (CLI11, so this one translation unit
// is compiled with exceptions), picks the backends (SocketCAN, POSIX serial that reopens its
// device after a hang-up, Linux clock, the candump recorder) and runs firmware/executive's
// SensorBox, which sees only the HAL interfaces.  --fault-log writes the box's fault state, on
// the box's own disk, whenever it changes: what BoxStatus says on the bus, also while the bus is
// down.  SIGINT / SIGTERM stop the loop at the end of the current period; the record and the
// fault log are flushed, the display started by --view (`scopekin display`, display_companion.hpp)
// stopped, a summary printed (and written as JSON with --stats) and the exit status
// says how it went:
//   0 stopped by a signal or --duration-s, 2 bad usage or a device that cannot be opened,
//   3 an I/O error while running (the record, the fault log or the stats could not be written).
#include <CLI/CLI.hpp>
#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "display_companion.hpp"
#include "executive/sensor_box.hpp"
#include "hal/clock.hpp"
#include "hal/linux/linux_clock.hpp"
#include "hal/linux/recording_can_bus.hpp"
#include "hal/posix_serial/reopening_serial_port.hpp"
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
    std::string fault_log_path;
    std::uint32_t serial_retry_ms{100};
    bool quiet{false};
    bool view{false};
    bool no_browser{false};
    scopekin::app::DisplayOptions display;
};

/// The box's objects: large (kinetics state, drivers), so they live here once, not on the stack.
struct Box {
    scopekin::hal::LinuxMonotonicClock clock{};
    scopekin::hal::SocketCanBus can{};
    std::unique_ptr<scopekin::hal::RecordingCanBus> recorder{};
    scopekin::hal::ReopeningSerialPort serial{clock};
    scopekin::executive::SensorBox box{};
};

const char* can_state_name(scopekin::protocol::CanState state) {
    switch (state) {
        case scopekin::protocol::CanState::error_active: return "error_active";
        case scopekin::protocol::CanState::warning: return "warning";
        case scopekin::protocol::CanState::error_passive: return "error_passive";
        case scopekin::protocol::CanState::bus_off: return "bus_off";
    }
    return "unknown";
}

const char* state_name(scopekin::protocol::BoxState state) {
    switch (state) {
        case scopekin::protocol::BoxState::starting: return "starting";
        case scopekin::protocol::BoxState::running: return "running";
        case scopekin::protocol::BoxState::degraded: return "degraded";
        case scopekin::protocol::BoxState::no_estimate: return "no_estimate";
    }
    return "unknown";
}

/// The box's fault state after a period: what the fault log compares and writes.
struct FaultState {
    scopekin::protocol::BoxState box_state{scopekin::protocol::BoxState::starting};
    scopekin::protocol::CanState can_state{scopekin::protocol::CanState::error_active};
    std::uint16_t driver_faults{0};
    std::uint8_t tracker_faults{0};
    std::uint32_t kinetic_faults{0};
    std::uint32_t period_overruns{0};  ///< so that release times between two lines are regular
    std::uint32_t serial_hangups{0};
    std::uint32_t serial_reopens{0};

    bool operator==(const FaultState&) const = default;
};

FaultState fault_state(const Box& box, bool serial) {
    FaultState state;
    state.box_state = box.box.box_state();
    state.can_state = box.box.can_health().state();
    state.driver_faults = box.box.box_faults();
    state.tracker_faults = box.box.tracker_faults();
    state.kinetic_faults = box.box.outputs().fault_flags;
    state.period_overruns = box.box.counters().period_overruns;
    if (serial) {
        state.serial_hangups = box.serial.reopen_counters().hangups;
        state.serial_reopens = box.serial.reopen_counters().reopens;
    }
    return state;
}

/// --fault-log: a CSV line for the first period, every period whose fault state (the bits, the
/// box and CAN state, the overrun and serial outage counts) differs from the previous line's, and
/// the last period.  Between two lines the periods were released one period apart (an overrun
/// writes a line), so the period of any time can be computed.  Flushed once a second and at
/// close().
class FaultLog {
public:
    bool open(const std::string& path) {
        file_ = std::fopen(path.c_str(), "w");
        if (file_ == nullptr) {
            return false;
        }
        write_line(
            "period,monotonic_us,box_state,can_state,driver_faults,tracker_faults,"
            "kinetic_faults,period_overruns,can_dropped,can_send_failures,serial_hangups,"
            "serial_reopens\n");
        return true;
    }
    [[nodiscard]] bool is_open() const { return file_ != nullptr; }

    /// After each period released at `release_us`.
    void period(const Box& box, bool serial, std::uint64_t release_us, bool last = false) {
        if (file_ == nullptr) {
            return;
        }
        const FaultState state = fault_state(box, serial);
        const std::uint32_t period = box.box.counters().periods;
        if (has_line_ && state == last_ && !last) {
            return;
        }
        if (last && has_line_ && period == last_period_) {
            return;  // that period's line is already there
        }
        const auto can = box.box.can_counters();
        std::array<char, 256> line{};
        std::snprintf(
            line.data(), line.size(), "%u,%llu,%s,%s,0x%04x,0x%02x,0x%04x,%u,%u,%u,%u,%u\n", period,
            static_cast<unsigned long long>(release_us), state_name(state.box_state),
            can_state_name(state.can_state), static_cast<unsigned>(state.driver_faults),
            static_cast<unsigned>(state.tracker_faults),
            static_cast<unsigned>(state.kinetic_faults), state.period_overruns, can.dropped,
            box.box.counters().send_failures, state.serial_hangups, state.serial_reopens);
        write_line(line.data());
        has_line_ = true;
        last_ = state;
        last_period_ = period;
        if (release_us >= next_flush_us_) {
            next_flush_us_ = release_us + 1000000U;
            if (std::fflush(file_) != 0) {
                ++write_errors_;
            }
        }
    }

    /// Flushes and closes; false if any line could not be written.
    bool close() {
        if (file_ == nullptr) {
            return true;
        }
        if (std::fclose(file_) != 0) {
            ++write_errors_;
        }
        file_ = nullptr;
        return write_errors_ == 0U;
    }
    [[nodiscard]] std::uint64_t lines() const { return lines_; }
    [[nodiscard]] std::uint64_t write_errors() const { return write_errors_; }

private:
    void write_line(const char* text) {
        if (std::fputs(text, file_) < 0) {
            ++write_errors_;
        } else {
            ++lines_;
        }
    }

    std::FILE* file_{nullptr};
    bool has_line_{false};
    FaultState last_{};
    std::uint32_t last_period_{0};
    std::uint64_t next_flush_us_{0};
    std::uint64_t lines_{0};
    std::uint64_t write_errors_{0};
};

nlohmann::json stats_json(const Box& box, bool serial, double elapsed_s, std::uint64_t record_lines,
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
                   {"can_recoveries", box.box.can_health().recoveries()},
                   {"receive_filtered", box.box.receive_filtered()},
                   {"backlog_periods", counters.backlog_periods},
                   {"late_frames", counters.late_frames}};
    json["handle_sensors"] = {{"force_torque_samples", handle.force_torque_samples},
                              {"insertion_roll_samples", handle.insertion_roll_samples},
                              {"bad_length", handle.bad_length},
                              {"out_of_range", handle.out_of_range},
                              {"sensor_status", handle.sensor_status},
                              {"counter_gaps", handle.counter_gaps},
                              {"stale_events", handle.stale_events},
                              {"late_samples", handle.late_samples}};
    json["last_output"] = {
        {"step_index", outputs.step_index},
        {"tip_path_mm", static_cast<double>(outputs.tip_path_mm.raw()) / 65536.0},
        {"fault_flags", outputs.fault_flags},
        {"self_lock_alarm", outputs.self_lock_alarm}};
    json["record"] = {{"lines", record_lines}, {"write_errors", record_errors}};
    if (serial) {
        const auto port = box.serial.counters();
        const auto& reopen = box.serial.reopen_counters();
        json["serial"] = {{"device_open", box.serial.device_open()},
                          {"bytes_received", port.bytes_received},
                          {"backend_errors", port.backend_errors},
                          {"hangups", reopen.hangups},
                          {"reopen_attempts", reopen.reopen_attempts},
                          {"reopens", reopen.reopens},
                          {"last_reopen_error", box.serial.last_reopen_error()}};
        const auto tracker = box.box.em_tracker().counters();
        json["em_tracker"] = {{"frames_ok", tracker.link.frames_ok},
                              {"poses_ok", tracker.poses_ok},
                              {"tip_forces_ok", tracker.tip_forces_ok},
                              {"bad_checksum", tracker.link.bad_checksum},
                              {"bad_length", tracker.link.bad_length},
                              {"unknown_type", tracker.link.unknown_type},
                              {"bytes_discarded", tracker.link.bytes_discarded},
                              {"buffer_overflows", tracker.link.buffer_overflows},
                              {"unknown_sensor", tracker.unknown_sensor},
                              {"out_of_range", tracker.out_of_range},
                              {"quaternion_norm", tracker.quaternion_norm},
                              {"timestamp_backwards", tracker.timestamp_backwards},
                              {"device_status", tracker.device_status},
                              {"stale_events", tracker.stale_events},
                              {"samples_dropped", tracker.samples_dropped},
                              {"serial_closed", tracker.serial_closed},
                              {"serial_errors", tracker.serial_errors}};
    }
    // What the box was built as: a test judges deadlines differently under sanitizers.
#if defined(__SANITIZE_ADDRESS__)
    constexpr bool kAddressSanitizer = true;
#else
    constexpr bool kAddressSanitizer = false;
#endif
#if defined(NDEBUG)
    constexpr bool kAssertions = false;
#else
    constexpr bool kAssertions = true;
#endif
    json["build"] = {{"address_sanitizer", kAddressSanitizer}, {"assertions", kAssertions}};
    return json;
}

/// What became of the display started by --view.
nlohmann::json display_json(const scopekin::app::DisplayCompanion& display,
                            const scopekin::app::DisplayOptions& options) {
    nlohmann::json json;
    json["program"] = options.program;
    json["port"] = options.port;
    json["ended_on_its_own"] = display.ended_on_its_own();
    json["exit_status"] =
        display.end_signal() == 0 ? nlohmann::json(display.exit_status()) : nlohmann::json(nullptr);
    json["end_signal"] = display.end_signal();
    json["how"] = scopekin::app::describe_end(display.exit_status(), display.end_signal());
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
    app.add_option("--serial-retry-ms", options.serial_retry_ms,
                   "after the serial device hangs up (adapter unplugged), try to reopen the same "
                   "path this often, ms; the tracker's link fault is flagged meanwhile")
        ->check(CLI::Range(10, 60000))
        ->capture_default_str();
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
    app.add_option("--fault-log", options.fault_log_path,
                   "write the fault state (CSV: period, monotonic time, box and CAN state, "
                   "driver/tracker/kinetic fault bits, counters) to FILE for the first period, "
                   "every period in which it changes, and the last");
    app.add_flag("--quiet", options.quiet, "no progress line (once a second) on stderr");
    auto* view = app.add_flag(
        "--view", options.view,
        "also show the box's page in a browser: starts `scopekin display --can IFACE` beside the "
        "box, a process of its own that reads what the box sends on the bus (it prints the page's "
        "address); it is stopped with the box, and if it ends the box goes on without it");
    app.add_option("--view-port", options.display.port,
                   "the display's port on 127.0.0.1 (0: any free port)")
        ->needs(view)
        ->capture_default_str();
    app.add_flag("--no-browser", options.no_browser,
                 "with --view: print the page's address, open no browser")
        ->needs(view);
    app.add_option("--display-program", options.display.program,
                   "with --view: the scopekin program to run the display with (looked up on PATH "
                   "unless it contains a '/')")
        ->needs(view)
        ->capture_default_str();
    app.set_version_flag("--version", "scopekin-box 0.1.0");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    }
    options.display.can_interface = options.can_interface;
    options.display.open_browser = !options.no_browser;
    options.display.quiet = options.quiet;

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
        if (!box.serial.open(options.serial_device.c_str(), options.baud,
                             options.serial_retry_ms * 1000U, serial_error)) {
            std::fprintf(stderr, "scopekin-box: %s\n", serial_error);
            return 2;
        }
        serial = &box.serial;
    }

    static FaultLog fault_log;
    if (!options.fault_log_path.empty() && !fault_log.open(options.fault_log_path)) {
        std::fprintf(stderr, "scopekin-box: cannot write the fault log %s: %s\n",
                     options.fault_log_path.c_str(), std::strerror(errno));
        return 2;
    }

    scopekin::executive::BoxConfig config;
    config.period_us = options.period_ms * 1000U;
    config.kinetics = scopekin::kinetics::default_config();  // the default tables and trees
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

    static scopekin::app::DisplayCompanion display;
    if (options.view && !display.start(options.display, error)) {
        std::fprintf(stderr, "scopekin-box: --view: %s\n", error.c_str());
        return 2;
    }

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
    std::uint64_t next_display_check_us = start_us + 1000000U;
    std::uint64_t last_release_us = start_us;
    scopekin::hal::SerialReopenCounters reported_reopen{};
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
        last_release_us = release_us;
        fault_log.period(box, serial != nullptr, release_us);
        if (serial != nullptr && !options.quiet) {
            const auto& reopen = box.serial.reopen_counters();
            if (reopen.hangups != reported_reopen.hangups) {
                std::fprintf(stderr,
                             "scopekin-box: t=%.3f s serial %s hung up; reopening it every %u ms\n",
                             static_cast<double>(release_us - start_us) / 1.0e6,
                             options.serial_device.c_str(), options.serial_retry_ms);
            }
            if (reopen.reopens != reported_reopen.reopens) {
                std::fprintf(stderr, "scopekin-box: t=%.3f s serial %s reopened (attempt %u)\n",
                             static_cast<double>(release_us - start_us) / 1.0e6,
                             options.serial_device.c_str(), reopen.reopen_attempts);
            }
            reported_reopen = reopen;
        }
        if (options.view && release_us >= next_display_check_us) {
            next_display_check_us += 1000000U;
            std::string how;
            if (display.ended_since_last_check(how)) {
                std::fprintf(stderr,
                             "scopekin-box: t=%.3f s the display ended (%s); the box goes on "
                             "without it (the display's own message says why; the box sets its "
                             "port with --view-port)\n",
                             static_cast<double>(release_us - start_us) / 1.0e6, how.c_str());
            }
        }
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
    display.stop();

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
    if (fault_log.is_open()) {
        fault_log.period(box, serial != nullptr, last_release_us, true);
        const std::uint64_t lines = fault_log.lines();
        if (!fault_log.close()) {
            std::fprintf(stderr,
                         "scopekin-box: %llu of %llu fault log lines could not be written to %s\n",
                         static_cast<unsigned long long>(fault_log.write_errors()),
                         static_cast<unsigned long long>(lines), options.fault_log_path.c_str());
            io_ok = false;
        }
    }
    nlohmann::json stats = stats_json(box, serial != nullptr, elapsed_s, record_lines,
                                      record_errors, stop_signal.load());
    if (options.view) stats["display"] = display_json(display, options.display);
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
