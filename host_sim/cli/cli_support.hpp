#pragma once
// What the commands share: output errors (exit status 3), files written as NAME.part and renamed
// when complete, a progress bar on stderr, writing JSON, and running a helper program.
//
// Every output file is written as NAME.part and renamed to NAME when it is complete; a run
// renames its summary (summary.json, a discrepancy's report.json, a shard's summary CSV) last of
// all. So a folder whose summary is missing holds an unfinished (killed) run, and a file under its
// final name is never a truncated one.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
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
    /// A file that is only ever finished complete.
    explicit PartFile(std::filesystem::path final_path);
    std::ofstream& stream() { return out_; }
    /// Closes and renames; returns the name it now has.
    std::filesystem::path finish(bool complete);

private:
    std::filesystem::path final_, incomplete_, part_;
    std::ofstream out_;
};

/// Progress on stderr: a single updating bar on a terminal, a line every 10 % otherwise (and, with
/// `stage`, a line whenever the stage changes: a long stage inside one 10 % step is not hidden).
class ProgressBar {
public:
    explicit ProgressBar(bool quiet);
    void update(const model::SimulationProgress& p);
    void update(double fraction, const std::string& text);
    /// As update, for a named stage: off a terminal, a new stage name is printed at once.
    void stage(double fraction, const std::string& name);
    /// Ends the bar (a terminal gets the last state drawn and a newline).
    void done();

private:
    void draw(double fraction, const std::string& text, bool force, bool new_stage = false);
    bool quiet_;
    bool tty_;
    bool drawn_ = false;
    bool pending_ = false;
    double pending_fraction_ = 0;
    std::string pending_text_;
    int last_decile_ = 0;
    std::string last_stage_;
    std::chrono::steady_clock::time_point last_draw_{};
};

/// Waits until a recorded time `t_us` (first recorded time `first_us`) is due at `pace` recorded
/// seconds per wall second from `wall_start` (pace 0: at once): `run --view`, `display LOG`.
void keep_pace(std::int64_t t_us, std::int64_t first_us, double pace,
               std::chrono::steady_clock::time_point wall_start);

/// Creates `dir` (OutputError if impossible) and removes the given old outputs in it, each
/// NAME and NAME.part, in the order given: list the summary first, so that no old summary stays
/// beside new files.
void prepare_directory(const std::filesystem::path& dir,
                       std::initializer_list<const char*> old_outputs);
/// Writes PATH.part and renames it to PATH (OutputError if either fails).
void write_json(const std::filesystem::path& path, const nlohmann::ordered_json& json);
/// Writes PATH.part only and returns its name; commit_part(PATH) renames it to PATH.
std::filesystem::path write_json_part(const std::filesystem::path& path,
                                      const nlohmann::ordered_json& json);
void commit_part(const std::filesystem::path& path);

/// Option checks with short messages (CLI11's own print a 309-digit bound, and an unsigned
/// option would take "-1" as 2^64 - 1): a positive, finite number of seconds; a whole number
/// from 0 to 2^64 - 1 (a seed).
CLI::Validator positive_seconds();
CLI::Validator whole_number();

/// Runs a program with these arguments (argv[0] is the program's path) and waits for it: no
/// shell, so every argument reaches the program as given, whatever characters it holds.
struct ProgramResult {
    bool started = false;
    int exit_status = -1;  ///< when it exited
    int signal = 0;        ///< when a signal ended it
    std::string error;     ///< why it could not be started
    /// "exited 1", "was killed by signal 9", "could not be started: ...".
    [[nodiscard]] std::string describe() const;
    [[nodiscard]] bool ok() const { return started && signal == 0 && exit_status == 0; }
};
ProgramResult run_program(const std::vector<std::string>& argv);

}  // namespace scopekin::cli
