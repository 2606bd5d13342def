#pragma once
// `scopekin static PROBLEM.json`: solves a static beam problem file and reports the
// convergence and the node poses (text, and JSON with --out).
#include <CLI/CLI.hpp>

namespace scopekin::cli {

void add_static_command(CLI::App& app);

}  // namespace scopekin::cli
