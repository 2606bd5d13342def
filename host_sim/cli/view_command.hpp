#pragma once
// `scopekin view DIR [--port N] [--no-browser] [--export FILE]`: a run in the browser
// (host_sim/view/README.md).
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

namespace scopekin::cli {

void add_view_command(CLI::App& app);

/// A command's live view options: --view (help `view_help`), --port and --no-browser (both need
/// --view). Returns the --view flag (other options may need it).
CLI::Option* add_live_view_options(CLI::App* cmd, bool& view, std::uint16_t& port, bool& no_browser,
                                   const std::string& view_help);

}  // namespace scopekin::cli
