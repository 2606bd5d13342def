#pragma once
// `scopekin simulate SCENARIO.json --out DIR`: runs a scenario file (README "Scenario files") and
// writes DIR/recording.csv and DIR/summary.json (a free beam scenario: its static solution).
#include <CLI/CLI.hpp>

namespace scopekin::cli {

void add_simulate_command(CLI::App& app);

}  // namespace scopekin::cli
