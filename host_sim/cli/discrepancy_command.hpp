#pragma once
#include <CLI/CLI.hpp>

namespace scopekin::cli {
/// `scopekin discrepancy RECORDING.csv [--model MODEL.json] --out DIR` (README "Discrepancy workflow").
void add_discrepancy_command(CLI::App& app);
}  // namespace scopekin::cli
