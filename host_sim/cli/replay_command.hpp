#pragma once
#include <CLI/CLI.hpp>

namespace scopekin::cli {
/// `scopekin replay CANDUMP.log --out DIR`: a candump log through the firmware.
void add_replay_command(CLI::App& app);
}  // namespace scopekin::cli
