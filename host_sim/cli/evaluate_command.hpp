#pragma once
// `scopekin evaluate MANIFEST --out DIR`, `scopekin evaluate-merge` and `scopekin evaluate-tune`:
// the scorecard of the box's estimators over a set of cases (host_sim/evaluate/README.md).
#include <CLI/CLI.hpp>

namespace scopekin::cli {
void add_evaluate_commands(CLI::App& app);
}  // namespace scopekin::cli
