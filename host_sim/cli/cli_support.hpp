#pragma once
// What the commands share: output errors (exit status 3), files written as NAME.part and renamed
// when complete, a progress bar on stderr, and writing JSON.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "model/scenario/simulation.hpp"

namespace scopekin::cli {

/// An output failure (exit status 3).
struct OutputError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// A file written as NAME.part and renamed when the run ends: NAME if complete, the
/// "incomplete" name otherwise.
class PartFile {
public:
    PartFile(std::filesystem::path final_path, std::filesystem::path incomplete_path);
    std::ofstream& stream() { return out_; }
    /// Closes and renames; returns the name it now has.
    std::filesystem::path finish(bool complete);

private:
    std::filesystem::path final_, incomplete_, part_;
    std::ofstream out_;
};

/// Progress on stderr: a single updating bar on a terminal, a line every 10 % otherwise.
class ProgressBar {
public:
    explicit ProgressBar(bool quiet);
    void update(const model::SimulationProgress& p);
    void update(double fraction, const std::string& text);
    /// Ends the bar (a terminal gets the last state drawn and a newline).
    void done();

private:
    void draw(double fraction, const std::string& text, bool force);
    bool quiet_;
    bool tty_;
    bool drawn_ = false;
    bool pending_ = false;
    double pending_fraction_ = 0;
    std::string pending_text_;
    int last_decile_ = 0;
    std::chrono::steady_clock::time_point last_draw_{};
};

/// Creates `dir` (OutputError if impossible) and removes the given old outputs in it.
void prepare_directory(const std::filesystem::path& dir,
                       std::initializer_list<const char*> old_outputs);
void write_json(const std::filesystem::path& path, const nlohmann::ordered_json& json);

}  // namespace scopekin::cli
