// The box's display beside the box (`scopekin-box --view`): `scopekin display --can IFACE`, started
// as a process of its own on the same interface, shows in a browser what the box sends on the bus
// (host_sim/view/README.md, "The box's display").  A process, not a server inside the box: the box
// keeps its firmware rules (no heap after init, no threads), a display that fails or is closed
// costs the box nothing, and the same display serves any box on the bus, bare metal included.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <string>

namespace scopekin::app {

struct DisplayOptions {
    std::string program = "scopekin";  ///< looked up on PATH unless it contains a '/'
    std::string can_interface;
    std::uint16_t port = 8765;  ///< 0: any free port (the display prints its address)
    bool open_browser = true;
    bool quiet = false;
};

class DisplayCompanion {
public:
    DisplayCompanion() = default;
    DisplayCompanion(const DisplayCompanion&) = delete;
    DisplayCompanion& operator=(const DisplayCompanion&) = delete;
    ~DisplayCompanion();

    /// Starts `PROGRAM display --can IFACE --port P [--no-browser] [--quiet]`; it inherits the
    /// box's stdout (its address) and stderr.  False, with the reason, when it cannot be started.
    bool start(const DisplayOptions& options, std::string& error);
    /// Whether it has ended since the last call (once); `how` then says how (exit status or signal).
    bool ended_since_last_check(std::string& how);
    /// Asks it to stop (SIGTERM) if it still runs and waits for it.
    void stop();

    /// Its exit status, or -1 while it runs or when a signal ended it.
    int exit_status() const { return exit_status_; }
    /// The signal that ended it, or 0.
    int end_signal() const { return end_signal_; }
    /// Whether it ended before the box asked it to.
    bool ended_on_its_own() const { return ended_on_its_own_; }

private:
    void record_end(int wait_status, bool on_its_own);

    pid_t pid_ = -1;
    bool ended_on_its_own_ = false;
    int exit_status_ = -1;
    int end_signal_ = 0;
};

/// "exit status N" or "signal N (NAME)".
std::string describe_end(int exit_status, int end_signal);

}  // namespace scopekin::app
