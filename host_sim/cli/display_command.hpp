#pragma once
// `scopekin display (LOG | --can IFACE)`: the box's display, from what the box sends on the CAN
// bus (host_sim/view/README.md, "The box's display").
#include <CLI/CLI.hpp>

namespace scopekin::cli {

void add_display_command(CLI::App& app);

}  // namespace scopekin::cli
