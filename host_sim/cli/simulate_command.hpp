#pragma once
// `scopekin simulate SCENARIO.json --out DIR`: runs a scenario file (model/scenario/README.md): a
// world scenario live through the sensors and the firmware (recording.csv, world.csv,
// firmware.csv, snapshots.json, summary.json), a free beam scenario statically.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

namespace scopekin::cli {

struct SimulateOptions {
    std::string scenario;
    std::string out;
    std::uint64_t seed = 1;
    bool quiet = false;
    double frames_hz = 0;  ///< frames.jsonl for `scopekin view` (world scenarios); 0: none
    bool view = false;     ///< stream to the browser view while running (world scenarios)
    std::uint16_t port = 8765;
    bool no_browser = false;
};

/// The command's work; returns its exit status (also used by `batch`). Throws ModelError for an
/// invalid scenario.
int run_simulate(const SimulateOptions& options);

void add_simulate_command(CLI::App& app);

}  // namespace scopekin::cli
