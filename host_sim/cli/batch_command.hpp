#pragma once
#include <CLI/CLI.hpp>

namespace scopekin::cli {
/// `scopekin batch MANIFEST --shard I/N --out DIR` and `scopekin batch-merge`.
void add_batch_commands(CLI::App& app);
}  // namespace scopekin::cli
