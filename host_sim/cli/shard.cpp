#include "host_sim/cli/shard.hpp"

#include <exception>

namespace scopekin::cli {

std::uint64_t fnv1a(const std::string& text) {
    std::uint64_t h = 0xcbf29ce484222325ULL;
    for (const char c : text) {
        h ^= static_cast<unsigned char>(c);
        h *= 0x100000001b3ULL;
    }
    return h;
}

bool parse_shard(const std::string& text, std::size_t& index, std::size_t& count) {
    const auto slash = text.find('/');
    if (slash == std::string::npos || slash == 0 || slash + 1 >= text.size()) return false;
    if (text[0] == '-' || text[0] == '+' || text[slash + 1] == '-' || text[slash + 1] == '+')
        return false;
    try {
        std::size_t used = 0;
        const unsigned long i = std::stoul(text.substr(0, slash), &used);
        if (used != slash) return false;
        const std::string n_text = text.substr(slash + 1);
        const unsigned long n = std::stoul(n_text, &used);
        if (used != n_text.size() || n == 0 || i >= n) return false;
        index = i;
        count = n;
        return true;
    } catch (const std::exception&) {
        return false;
    }
}

}  // namespace scopekin::cli
