#pragma once
#include <CLI/CLI.hpp>

#include <string>

#include "host_sim/recording/recording_reader.hpp"

namespace scopekin::cli {

struct RunOptions {
    std::string recording;
    std::string out;
    double gap_threshold_s = 0.05;
    double max_gap_s = recording::kDefaultMaxGap_s;
    bool quiet = false;
};

/// The command's work; returns its exit status (also used by `batch`).
int run_recording(const RunOptions& options);

/// `scopekin run RECORDING.csv --out DIR`: a recording through the firmware.
void add_run_command(CLI::App& app);
}  // namespace scopekin::cli
