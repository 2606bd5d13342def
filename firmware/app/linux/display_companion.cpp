#include "display_companion.hpp"

#include <sys/wait.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <vector>

#include "hal/linux/spawn_program.hpp"

namespace scopekin::app {

DisplayCompanion::~DisplayCompanion() {
    stop();
}

bool DisplayCompanion::start(const DisplayOptions& options, std::string& error) {
    std::vector<std::string> args = {options.program, "display",
                                     "--can",         options.can_interface,
                                     "--port",        std::to_string(options.port)};
    if (!options.open_browser) args.emplace_back("--no-browser");
    if (options.quiet) args.emplace_back("--quiet");
    std::vector<char*> argv;
    for (auto& a : args)
        argv.push_back(a.data());
    argv.push_back(nullptr);
    // The box catches SIGINT/SIGTERM: the display starts with the default dispositions and sets
    // up its own.
    pid_t pid = -1;
    const int failed = hal::spawn_program(pid, options.program.c_str(), nullptr, argv.data());
    if (failed != 0) {
        error = "cannot start the display '" + options.program + "': " + std::strerror(failed);
        return false;
    }
    pid_ = pid;
    return true;
}

void DisplayCompanion::record_end(int wait_status, bool on_its_own) {
    ended_on_its_own_ = on_its_own;
    pid_ = -1;
    if (WIFEXITED(wait_status)) exit_status_ = WEXITSTATUS(wait_status);
    if (WIFSIGNALED(wait_status)) end_signal_ = WTERMSIG(wait_status);
}

bool DisplayCompanion::ended_since_last_check(std::string& how) {
    if (pid_ <= 0) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) != pid_) return false;
    record_end(status, true);
    how = describe_end(exit_status_, end_signal_);
    return true;
}

void DisplayCompanion::stop() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    int status = 0;
    pid_t waited = -1;
    do {
        waited = waitpid(pid_, &status, 0);
    } while (waited < 0 && errno == EINTR);
    if (waited == pid_) {
        record_end(status, false);
    } else {
        pid_ = -1;
    }
}

std::string describe_end(int exit_status, int end_signal) {
    if (end_signal != 0) {
        const char* name = sigabbrev_np(end_signal);
        return "signal " + std::to_string(end_signal) +
               (name != nullptr ? std::string(" (SIG") + name + ")" : "");
    }
    return "exit status " + std::to_string(exit_status);
}

}  // namespace scopekin::app
