#pragma once
// Splitting a list of entries into N shards (`scopekin batch`, `scopekin evaluate`): an entry
// belongs to shard FNV-1a-64(its key) mod N, so adding or removing entries never moves the
// others between shards.
#include <cstddef>
#include <cstdint>
#include <string>

namespace scopekin::cli {

/// FNV-1a 64 of the text (offset basis 0xcbf29ce484222325, prime 0x100000001b3).
std::uint64_t fnv1a(const std::string& text);

/// The shard of `key` among `shards` (> 0).
inline std::size_t shard_of(const std::string& key, std::size_t shards) {
    return static_cast<std::size_t>(fnv1a(key) % shards);
}

/// Parses "I/N" with 0 <= I < N (no signs, no spaces); false if it is not one.
bool parse_shard(const std::string& text, std::size_t& index, std::size_t& count);

}  // namespace scopekin::cli
