#include "host_sim/cli/cli_support.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <limits>
#include <system_error>
#include <thread>

#include "model/io/strict_json.hpp"

extern char** environ;

namespace scopekin::cli {

namespace fs = std::filesystem;

namespace {

fs::path part_of(const fs::path& path) {
    return path.string() + ".part";
}

void rename_part(const fs::path& part, const fs::path& target) {
    std::error_code ec;
    fs::rename(part, target, ec);
    if (ec)
        throw OutputError("cannot rename " + part.string() + " to " + target.string() + ": " +
                          ec.message());
}

}  // namespace

void keep_pace(std::int64_t t_us, std::int64_t first_us, double pace,
               std::chrono::steady_clock::time_point wall_start) {
    if (!(pace > 0)) return;
    const auto due =
        wall_start +
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
            std::chrono::duration<double>(static_cast<double>(t_us - first_us) * 1e-6 / pace));
    std::this_thread::sleep_until(due);
}

PartFile::PartFile(fs::path final_path, fs::path incomplete_path)
    : final_(std::move(final_path)),
      incomplete_(std::move(incomplete_path)),
      part_(part_of(final_)) {
    out_.open(part_, std::ios::binary);
    if (!out_) throw OutputError("cannot write " + part_.string());
}

PartFile::PartFile(fs::path final_path) : PartFile(final_path, final_path) {}

fs::path PartFile::finish(bool complete) {
    out_.close();
    if (out_.fail()) throw OutputError("error while writing " + part_.string());
    const fs::path& target = complete ? final_ : incomplete_;
    rename_part(part_, target);
    return target;
}

ProgressBar::ProgressBar(bool quiet) : quiet_(quiet), tty_(isatty(fileno(stderr)) != 0) {}

void ProgressBar::update(const model::SimulationProgress& p) {
    if (!(p.end_s > 0.0)) return;
    char text[120];
    std::snprintf(text, sizeof text, "t=%.1f/%.1f s  contacts %zu  F %.1f N", p.time_s, p.end_s,
                  p.contacts, p.handle_force_N);
    update(p.time_s / p.end_s, text);
}

void ProgressBar::update(double fraction, const std::string& text) {
    if (quiet_) return;
    draw(std::clamp(fraction + 1e-9, 0.0, 1.0), text, false);
}

void ProgressBar::stage(double fraction, const std::string& name) {
    if (quiet_) return;
    const bool changed = name != last_stage_;
    last_stage_ = name;
    draw(std::clamp(fraction + 1e-9, 0.0, 1.0), name, false, changed);
}

void ProgressBar::draw(double fraction, const std::string& text, bool force, bool new_stage) {
    const int filled = static_cast<int>(std::floor(fraction * 10.0 + 1e-9));
    char line[200];
    std::snprintf(line, sizeof line, "[%s%s] %3d%% %s",
                  std::string(static_cast<std::size_t>(filled), '#').c_str(),
                  std::string(static_cast<std::size_t>(10 - filled), ' ').c_str(),
                  static_cast<int>(std::floor(fraction * 100.0 + 1e-9)), text.c_str());
    const auto now = std::chrono::steady_clock::now();
    if (tty_) {
        if (!force && fraction < 1.0 && now - last_draw_ < std::chrono::milliseconds(100)) {
            pending_ = true;
            pending_fraction_ = fraction;
            pending_text_ = text;
            return;
        }
        pending_ = false;
        last_draw_ = now;
        std::cerr << "\r" << line << "   " << std::flush;
        drawn_ = true;
    } else {
        const int decile = static_cast<int>(std::floor(fraction * 10.0 + 1e-9));
        if (decile <= last_decile_ && !new_stage) return;
        last_decile_ = std::max(decile, last_decile_);
        std::cerr << line << "\n" << std::flush;
    }
}

void ProgressBar::done() {
    if (quiet_ || !tty_) return;
    if (pending_) draw(pending_fraction_, pending_text_, true);
    if (drawn_) std::cerr << "\n" << std::flush;
    drawn_ = pending_ = false;
}

void prepare_directory(const fs::path& dir, std::initializer_list<const char*> old_outputs) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
        throw OutputError("cannot create the output directory " + dir.string() +
                          (ec ? ": " + ec.message() : ""));
    for (const char* name : old_outputs) {
        for (const fs::path& old : {dir / name, part_of(dir / name)}) {
            fs::remove(old, ec);
            if (ec)
                throw OutputError("cannot remove the old " + old.string() + ": " + ec.message());
        }
    }
}

fs::path write_json_part(const fs::path& path, const nlohmann::ordered_json& json) {
    const fs::path part = part_of(path);
    std::ofstream out(part, std::ios::binary);
    out << json.dump(2) << "\n";
    out.close();
    if (!out) throw OutputError("cannot write " + part.string());
    return part;
}

void commit_part(const fs::path& path) {
    rename_part(part_of(path), path);
}

void write_json(const fs::path& path, const nlohmann::ordered_json& json) {
    write_json_part(path, json);
    commit_part(path);
}

CLI::Validator positive_seconds() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            double value = 0;
            const char* end = text.data() + text.size();
            const auto r = std::from_chars(text.data(), end, value);
            if (text.empty() || r.ec != std::errc() || r.ptr != end || !std::isfinite(value) ||
                !(value > 0))
                return model::io::quote_text(text) + " is not a positive, finite number of seconds";
            return {};
        },
        "SECONDS");
}

CLI::Validator whole_number() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            std::uint64_t value = 0;
            const char* end = text.data() + text.size();
            const auto r = std::from_chars(text.data(), end, value);
            if (text.empty() || r.ec != std::errc() || r.ptr != end)
                return model::io::quote_text(text) + " is not a whole number from 0 to " +
                       std::to_string(std::numeric_limits<std::uint64_t>::max());
            return {};
        },
        "UINT");
}

std::string ProgramResult::describe() const {
    if (!started) return "could not be started: " + error;
    if (signal != 0)
        return "was ended by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
    return "exited " + std::to_string(exit_status);
}

ProgramResult run_program(const std::vector<std::string>& argv) {
    ProgramResult result;
    if (argv.empty()) {
        result.error = "no program";
        return result;
    }
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const std::string& a : argv)
        args.push_back(const_cast<char*>(a.c_str()));  // posix_spawn's signature; not written
    args.push_back(nullptr);
    std::fflush(stdout);  // the child's output comes after ours
    std::fflush(stderr);
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, args[0], nullptr, nullptr, args.data(), environ);
    if (spawned != 0) {
        result.error = argv[0] + ": " + std::strerror(spawned);
        return result;
    }
    result.started = true;
    int status = 0;
    while (waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) {
            result.started = false;
            result.error = std::string("waiting for ") + argv[0] + ": " + std::strerror(errno);
            return result;
        }
    }
    if (WIFEXITED(status)) result.exit_status = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
    return result;
}

}  // namespace scopekin::cli
