#include "host_sim/cli/cli_support.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <system_error>

namespace scopekin::cli {

namespace fs = std::filesystem;

PartFile::PartFile(fs::path final_path, fs::path incomplete_path)
    : final_(std::move(final_path)),
      incomplete_(std::move(incomplete_path)),
      part_(final_.string() + ".part") {
    out_.open(part_);
    if (!out_) throw OutputError("cannot write " + part_.string());
}

fs::path PartFile::finish(bool complete) {
    out_.close();
    if (out_.fail()) throw OutputError("error while writing " + part_.string());
    const fs::path& target = complete ? final_ : incomplete_;
    std::error_code ec;
    fs::rename(part_, target, ec);
    if (ec)
        throw OutputError("cannot rename " + part_.string() + " to " + target.string() + ": " +
                          ec.message());
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

void ProgressBar::draw(double fraction, const std::string& text, bool force) {
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
        if (decile <= last_decile_) return;
        last_decile_ = decile;
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
        fs::remove(dir / name, ec);
        if (ec)
            throw OutputError("cannot remove the old " + (dir / name).string() + ": " +
                              ec.message());
    }
}

void write_json(const fs::path& path, const nlohmann::ordered_json& json) {
    std::ofstream out(path);
    out << json.dump(2) << "\n";
    out.close();
    if (!out) throw OutputError("cannot write " + path.string());
}

}  // namespace scopekin::cli
