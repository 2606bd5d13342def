// vm_peer.cpp — scopekin-vm-peer: the box's peers in the SocketCAN VM tests (guest side).
//
// The can-utils tools pace themselves on the wall clock (canplayer) and exit at the first
// failed write; the fault tests step the wall clock, take the interface down and fill its send
// queue, so they need peers that do neither.  Three commands:
//
//   scopekin-vm-peer now
//       prints CLOCK_MONOTONIC in µs: the guest scripts mark when they caused a fault, on the
//       clock of the box's periods and fault log.
//   scopekin-vm-peer play --can IFACE --log FILE [--report FILE]
//       sends the frames of a candump log on IFACE through hal::SocketCanBus, each at its time
//       stamp relative to the first, on CLOCK_MONOTONIC (absolute deadlines, no drift; late
//       frames are sent at once).  A frame the interface refuses (down: bus_off; send queue full:
//       timeout) is counted and skipped, as a sensor's frame is lost on a bus the box cannot
//       hear, never retried.  Stops at the end of the log or on SIGINT/SIGTERM.  The report
//       lists the episodes in which frames went out a period (5 ms) or more late ([when the
//       first was due, when the last went out, the most any was late], µs): when a starved
//       player paused the inputs.
//       SIGUSR1 / SIGUSR2 step the wall clock (CLOCK_REALTIME) an hour forward / back before the
//       next frame; the report lists each step as [CLOCK_MONOTONIC µs just before, just after,
//       seconds].  Stepping here, not with `date -s`, keeps the guest quiet at the step: under
//       TCG starting any program takes ~0.1 s of the only CPU, which would pause the inputs and
//       hide what the step itself does to the box.
//   scopekin-vm-peer tracker --link PATH [--rate-hz N] [--report FILE]
//       a test-bench EM tracker on a new pseudo-terminal whose slave is reachable at PATH (a
//       symlink, replaced atomically, like a udev link): valid frames of the four pose sensors
//       and the tip force, round robin, each source at N Hz (default 30), device time =
//       CLOCK_MONOTONIC µs modulo 2^32 (a restarted tracker continues it).  Frames are written
//       only while someone has had the line open for 50 ms (the master polls POLLHUP; the
//       others are counted as unconnected), so `frames` is what a reader could get; frames the slave's queue cannot
//       take are counted and dropped.  SIGUSR1 stops streaming (the line stays up)
//       and writes the report; SIGINT/SIGTERM remove PATH, close the pty (the reader sees a
//       hang-up: an unplugged adapter), write the report and exit.  The report lists the
//       episodes in which frames went out late, like play's.
//
// Reports are one JSON object.  Exit status: 0 done, 1 a system call failed, 2 bad usage.
// Test support, not the box: built on x86-64 Linux with the VM tests (tests/socketcan_vm).
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hal/candump/candump_log.hpp"
#include "hal/socketcan/socketcan_bus.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace {

std::atomic<int> stop_signal{0};
std::atomic<bool> pause_requested{false};
std::atomic<int> clock_steps_requested{0};  // +1 per SIGUSR1, -1 per SIGUSR2 (play)

extern "C" void on_stop(int signal_number) {
    stop_signal.store(signal_number);
}
extern "C" void on_pause(int) {
    pause_requested.store(true);
}
extern "C" void on_step(int signal_number) {
    clock_steps_requested.fetch_add(signal_number == SIGUSR1 ? 1 : -1);
}

void install_signals(bool with_pause, bool with_steps = false) {
    struct sigaction action {};
    action.sa_handler = on_stop;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
    if (with_pause) {
        action.sa_handler = on_pause;
        sigaction(SIGUSR1, &action, nullptr);
    }
    if (with_steps) {
        action.sa_handler = on_step;
        sigaction(SIGUSR1, &action, nullptr);
        sigaction(SIGUSR2, &action, nullptr);
    }
}

std::uint64_t monotonic_us() {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    return static_cast<std::uint64_t>(now.tv_sec) * 1000000U +
           static_cast<std::uint64_t>(now.tv_nsec) / 1000U;
}

/// Sleeps until `deadline_us` on CLOCK_MONOTONIC (returns early on a stop signal only).
void sleep_until_us(std::uint64_t deadline_us) {
    timespec deadline{};
    deadline.tv_sec = static_cast<time_t>(deadline_us / 1000000U);
    deadline.tv_nsec = static_cast<long>((deadline_us % 1000000U) * 1000U);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR &&
           stop_signal.load() == 0) {
    }
}

/// Steps CLOCK_REALTIME by `seconds`; appends [monotonic before, after, seconds] to `steps`.
bool step_wall_clock(int seconds, std::string& steps) {
    const std::uint64_t before_us = monotonic_us();
    timespec now{};
    clock_gettime(CLOCK_REALTIME, &now);
    now.tv_sec += seconds;
    const bool ok = clock_settime(CLOCK_REALTIME, &now) == 0;
    const std::uint64_t after_us = monotonic_us();
    steps += (steps.empty() ? "[" : ", [") + std::to_string(before_us) + ", " +
             std::to_string(after_us) + ", " + std::to_string(seconds) + "]";
    return ok;
}

int usage() {
    std::fprintf(stderr,
                 "usage: scopekin-vm-peer now\n"
                 "       scopekin-vm-peer play --can IFACE --log FILE [--report FILE]\n"
                 "       scopekin-vm-peer tracker --link PATH [--rate-hz N] [--report FILE]\n");
    return 2;
}

bool write_report(const std::string& path, const std::string& json) {
    if (path.empty()) {
        std::printf("%s\n", json.c_str());
        return true;
    }
    std::ofstream out(path);
    out << json << "\n";
    return static_cast<bool>(out);
}

/// Episodes in which a peer sent a period (5 ms) or more late: when the guest starved it, its
/// data paused for the box (the checks judge staleness only outside them).  An episode lasts from
/// the first late frame's due time to the moment the last late frame of a run of them went out;
/// once the list is full, later episodes are merged into the last one (still covered).
class Lateness {
public:
    /// A frame due at `due_us` went out at `now_us`.
    void sent(std::uint64_t due_us, std::uint64_t now_us) {
        const std::uint64_t late_us = now_us > due_us ? now_us - due_us : 0U;
        if (late_us > max_us_) {
            max_us_ = late_us;
        }
        if (late_us < kLateUs) {
            in_episode_ = false;
            return;
        }
        if (!in_episode_ && episodes_.size() < kMaxEpisodes) {
            episodes_.push_back({due_us, now_us, late_us});
        } else {
            episodes_.back().end_us = now_us;
            if (late_us > episodes_.back().late_us) {
                episodes_.back().late_us = late_us;
            }
        }
        in_episode_ = true;
    }
    /// `"late_max_ms": N, "late_episodes": [[due_us, end_us, late_us], ...]`
    [[nodiscard]] std::string json() const {
        std::string text =
            "\"late_max_ms\": " + std::to_string(max_us_ / 1000U) + ", \"late_episodes\": [";
        for (std::size_t k = 0; k < episodes_.size(); ++k) {
            text += (k == 0U ? "[" : ", [") + std::to_string(episodes_[k].due_us) + ", " +
                    std::to_string(episodes_[k].end_us) + ", " +
                    std::to_string(episodes_[k].late_us) + "]";
        }
        return text + "]";
    }

private:
    struct Episode {
        std::uint64_t due_us;   ///< when the first late frame was due (CLOCK_MONOTONIC)
        std::uint64_t end_us;   ///< when the last late frame went out
        std::uint64_t late_us;  ///< the most any frame of the episode was late
    };
    static constexpr std::uint64_t kLateUs = 5000;
    static constexpr std::size_t kMaxEpisodes = 1000;
    std::vector<Episode> episodes_;
    bool in_episode_{false};
    std::uint64_t max_us_{0};
};

// --- play ----------------------------------------------------------------------------------------

int play(const std::string& interface, const std::string& log_path,
         const std::string& report_path) {
    std::ifstream log(log_path);
    if (!log) {
        std::fprintf(stderr, "scopekin-vm-peer: cannot read %s\n", log_path.c_str());
        return 1;
    }
    std::vector<scopekin::hal::CandumpRecord> records;
    std::string line;
    for (std::size_t number = 1; std::getline(log, line); ++number) {
        scopekin::hal::CandumpRecord record;
        const auto result = scopekin::hal::parse_candump_line(line, record);
        if (result == scopekin::hal::CandumpParse::blank) {
            continue;
        }
        if (result != scopekin::hal::CandumpParse::ok) {
            std::fprintf(stderr, "scopekin-vm-peer: %s:%zu: %s\n", log_path.c_str(), number,
                         scopekin::hal::describe(result));
            return 2;
        }
        records.push_back(record);
    }

    scopekin::hal::SocketCanBus bus;
    scopekin::hal::SocketCanConfig config;
    config.interface = interface;
    static constexpr std::uint32_t kNothing[] = {0x7FFU};  // receive (almost) nothing
    config.receive_ids = kNothing;
    config.receive_error_frames = false;
    std::string error;
    if (!bus.open(config, error)) {
        std::fprintf(stderr, "scopekin-vm-peer: %s\n", error.c_str());
        return 1;
    }
    install_signals(false, true);

    std::uint64_t attempted = 0;  // frames whose time came (all of them unless stopped)
    std::uint64_t sent = 0;
    std::uint64_t interface_down = 0;  // CanStatus::bus_off (ENETDOWN)
    std::uint64_t queue_full = 0;      // CanStatus::timeout (ENOBUFS, EAGAIN)
    std::uint64_t other_failures = 0;
    std::uint64_t clock_step_failures = 0;
    std::string clock_steps;
    Lateness lateness;
    const std::uint64_t start_us = monotonic_us();
    const std::uint64_t first_stamp_us = records.empty() ? 0U : records.front().timestamp_us;
    for (const auto& record : records) {
        if (stop_signal.load() != 0) {
            break;
        }
        const std::uint64_t offset_us =
            record.timestamp_us > first_stamp_us ? record.timestamp_us - first_stamp_us : 0U;
        const std::uint64_t due_us = start_us + offset_us;
        sleep_until_us(due_us);
        for (int requested = clock_steps_requested.exchange(0); requested != 0;) {
            const int direction = requested > 0 ? 1 : -1;
            if (!step_wall_clock(direction * 3600, clock_steps)) {
                ++clock_step_failures;
            }
            requested -= direction;
        }
        lateness.sent(due_us, monotonic_us());
        ++attempted;
        switch (bus.send(record.frame, 0U)) {
            case scopekin::hal::CanStatus::ok: ++sent; break;
            case scopekin::hal::CanStatus::bus_off: ++interface_down; break;
            case scopekin::hal::CanStatus::timeout: ++queue_full; break;
            default: ++other_failures; break;
        }
    }
    std::string json =
        "{\"frames\": " + std::to_string(records.size()) +
        ", \"attempted\": " + std::to_string(attempted) + ", \"sent\": " + std::to_string(sent) +
        ", \"interface_down\": " + std::to_string(interface_down) +
        ", \"queue_full\": " + std::to_string(queue_full) +
        ", \"other_failures\": " + std::to_string(other_failures) +
        ", \"stopped_by_signal\": " + std::to_string(stop_signal.load()) + ", \"clock_steps\": [" +
        clock_steps + "]" + ", \"clock_step_failures\": " + std::to_string(clock_step_failures) +
        ", " + lateness.json() + "}";
    return write_report(report_path, json) ? 0 : 1;
}

// --- tracker -------------------------------------------------------------------------------------

struct TrackerReport {
    std::uint64_t frames{0};  ///< written into the line while it was open
    std::uint64_t bytes{0};
    std::uint64_t dropped_frames{0};      ///< the line was open but took nothing (queue full)
    std::uint64_t unconnected_frames{0};  ///< not written: nobody had the line open
};

std::string tracker_json(const TrackerReport& report, const Lateness& lateness, const char* state) {
    return "{\"frames\": " + std::to_string(report.frames) +
           ", \"bytes\": " + std::to_string(report.bytes) +
           ", \"dropped_frames\": " + std::to_string(report.dropped_frames) +
           ", \"unconnected_frames\": " + std::to_string(report.unconnected_frames) +
           ", \"state\": \"" + state + "\", " + lateness.json() + "}";
}

int tracker(const std::string& link, std::uint32_t rate_hz, const std::string& report_path) {
    const int master = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC | O_NONBLOCK);
    std::array<char, 128> slave_path{};
    if (master < 0 || ::grantpt(master) != 0 || ::unlockpt(master) != 0 ||
        ::ptsname_r(master, slave_path.data(), slave_path.size()) != 0) {
        std::fprintf(stderr, "scopekin-vm-peer: cannot create a pseudo-terminal: %s\n",
                     std::strerror(errno));
        return 1;
    }
    // Raw mode on the slave before anyone reads it (no echo back into the master, no CR/LF
    // translation); the box sets it again when it opens the line.
    const int slave = ::open(slave_path.data(), O_RDWR | O_NOCTTY | O_CLOEXEC);
    termios settings{};
    if (slave < 0 || ::tcgetattr(slave, &settings) != 0) {
        std::fprintf(stderr, "scopekin-vm-peer: cannot open %s: %s\n", slave_path.data(),
                     std::strerror(errno));
        return 1;
    }
    ::cfmakeraw(&settings);
    (void)::tcsetattr(slave, TCSANOW, &settings);
    ::close(slave);
    const std::string temporary = link + ".new";
    (void)::unlink(temporary.c_str());
    if (::symlink(slave_path.data(), temporary.c_str()) != 0 ||
        ::rename(temporary.c_str(), link.c_str()) != 0) {
        std::fprintf(stderr, "scopekin-vm-peer: cannot link %s to %s: %s\n", link.c_str(),
                     slave_path.data(), std::strerror(errno));
        return 1;
    }
    install_signals(true);
    std::fprintf(stderr, "scopekin-vm-peer: EM tracker on %s (%s), %u Hz per source\n",
                 link.c_str(), slave_path.data(), rate_hz);

    TrackerReport report;
    Lateness lateness;
    constexpr std::uint32_t kSources = 5;  // four pose sensors, then the tip force
    const std::uint64_t interval_us = 1000000U / (static_cast<std::uint64_t>(rate_hz) * kSources);
    std::uint64_t due_us = monotonic_us();
    bool paused = false;
    constexpr std::uint64_t kSettleUs = 50'000;
    std::uint64_t connected_since_us = 0;  // when the line was found open (0: not open)
    for (std::uint64_t event = 0; stop_signal.load() == 0; ++event) {
        if (pause_requested.load() && !paused) {
            paused = true;
            (void)write_report(report_path, tracker_json(report, lateness, "paused"));
        }
        due_us += interval_us;
        sleep_until_us(due_us);
        if (paused) {
            continue;
        }
        lateness.sent(due_us, monotonic_us());
        std::array<std::uint8_t, scopekin::protocol::kEmTrackerMaxFrameSize> frame{};
        std::size_t size = 0;
        const auto device_time = static_cast<std::uint32_t>(monotonic_us());
        const auto source = static_cast<std::uint32_t>(event % kSources);
        if (source < 4U) {
            scopekin::protocol::EmPoseMessage pose;
            pose.device_time_us = device_time;
            pose.sensor_id = static_cast<std::uint8_t>(source);
            pose.status = 0;
            // A scope along x, the sensors 200 mm apart; identity orientation (Q2.14 1.0).
            pose.position_um = {static_cast<std::int32_t>(source) * 200000, 10000, -5000};
            pose.orientation_q14 = {16384, 0, 0, 0};
            size = scopekin::protocol::encode_em_pose(pose, frame);
        } else {
            scopekin::protocol::TipForceMessage force;
            force.device_time_us = device_time;
            force.status = 0;
            force.force_mN = {50, -30, 400};
            size = scopekin::protocol::encode_tip_force(force, frame);
        }
        // POLLHUP on the master: nobody has the line open (the box has not opened it yet, or
        // closed it): the frame goes nowhere and is not counted.  For kSettleUs after someone
        // opened it nothing is written either: the box flushes the line right after opening it,
        // and a frame written in between would be lost (under load that gap is not short).
        pollfd line{master, POLLOUT, 0};
        if (::poll(&line, 1, 0) >= 0 && (line.revents & POLLHUP) != 0) {
            ++report.unconnected_frames;
            connected_since_us = 0;
            continue;
        }
        const std::uint64_t now_us = monotonic_us();
        if (connected_since_us == 0U) {
            connected_since_us = now_us;
        }
        if (now_us - connected_since_us < kSettleUs) {
            ++report.unconnected_frames;
            continue;
        }
        const ssize_t written = ::write(master, frame.data(), size);
        if (written == static_cast<ssize_t>(size)) {
            ++report.frames;
            report.bytes += size;
        } else {
            ++report.dropped_frames;  // nobody reads the line: a real tracker's bytes are lost too
        }
    }
    (void)::unlink(link.c_str());
    ::close(master);
    return write_report(report_path, tracker_json(report, lateness, "stopped")) ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        return usage();
    }
    const std::string_view command = argv[1];
    if (command == "now" && argc == 2) {
        std::printf("%llu\n", static_cast<unsigned long long>(monotonic_us()));
        return 0;
    }
    std::string interface;
    std::string log;
    std::string link;
    std::string report;
    unsigned long rate_hz = 30;
    for (int i = 2; i < argc; ++i) {
        const std::string_view option = argv[i];
        if (i + 1 >= argc) {
            return usage();
        }
        const char* value = argv[++i];
        if (option == "--can") {
            interface = value;
        } else if (option == "--log") {
            log = value;
        } else if (option == "--link") {
            link = value;
        } else if (option == "--report") {
            report = value;
        } else if (option == "--rate-hz") {
            char* end = nullptr;
            rate_hz = std::strtoul(value, &end, 10);
            if (end == value || *end != '\0' || rate_hz < 1U || rate_hz > 1000U) {
                return usage();
            }
        } else {
            return usage();
        }
    }
    if (command == "play" && !interface.empty() && !log.empty() && link.empty()) {
        return play(interface, log, report);
    }
    if (command == "tracker" && !link.empty() && interface.empty() && log.empty()) {
        return tracker(link, static_cast<std::uint32_t>(rate_hz), report);
    }
    return usage();
}
