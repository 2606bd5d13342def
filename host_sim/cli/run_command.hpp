#pragma once
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

#include "host_sim/recording/recording_reader.hpp"

namespace scopekin::cli {

struct RunOptions {
    std::string recording;
    std::string out;
    double gap_threshold_s = 0.05;
    double max_gap_s = recording::kDefaultMaxGap_s;
    bool quiet = false;
    bool view = false;  ///< the box's page (what the box knows, no truth), live while it runs
    std::uint16_t port = 8765;
    bool no_browser = false;
    double pace = 1.0;  ///< with view: recorded seconds per wall second (0: as fast as it goes)
};

/// The command's work; returns its exit status (also used by `batch`).
int run_recording(const RunOptions& options);

/// `scopekin run RECORDING.csv --out DIR`: a recording through the firmware.
void add_run_command(CLI::App& app);
}  // namespace scopekin::cli
