#pragma once
#include <CLI/CLI.hpp>

namespace scopekin::cli {
/// `scopekin discrepancy RECORDING.csv [--model MODEL.json] --out DIR` (host_sim/discrepancy/README.md).
void add_discrepancy_command(CLI::App& app);
}  // namespace scopekin::cli
