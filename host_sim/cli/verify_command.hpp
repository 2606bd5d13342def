#pragma once
// `scopekin verify`: runs the reference model's verification cases and prints a table
// (or JSON), exit status 0 only if every check passes.
#include <CLI/CLI.hpp>

namespace scopekin::cli {

void add_verify_command(CLI::App& app);

}  // namespace scopekin::cli
