#pragma once
#include <CLI/CLI.hpp>

namespace scopekin::cli {
/// `scopekin demo`: the bundled simulated colonoscopy through the firmware, with plots.
void add_demo_command(CLI::App& app);
}  // namespace scopekin::cli
