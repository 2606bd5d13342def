#pragma once
// `scopekin view DIR [--port N] [--no-browser] [--export FILE]`: a run in the browser
// (host_sim/view/README.md).
#include <CLI/CLI.hpp>

namespace scopekin::cli {

void add_view_command(CLI::App& app);

}  // namespace scopekin::cli
