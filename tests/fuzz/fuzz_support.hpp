// fuzz_support.hpp — what every fuzz target here shares: an invariant check that reports its
// file and line and traps (libFuzzer keeps the input), and a reader that turns the fuzzer's bytes
// into a script of choices (past the end it reads zeros).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <span>

namespace scopekin::fuzz {

inline void require_at(bool condition, const char* file, int line) {
    if (!condition) {
        std::fprintf(stderr, "invariant violated: %s:%d\n", file, line);
        __builtin_trap();
    }
}

/// The fuzzer's input read front to back as bytes, 16- and 32-bit little-endian words and spans.
class Script {
public:
    Script(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
    [[nodiscard]] bool done() const { return offset_ >= size_; }
    std::uint8_t byte() { return offset_ < size_ ? data_[offset_++] : std::uint8_t{0}; }
    std::uint16_t u16() {
        const auto low = byte();
        return static_cast<std::uint16_t>(low | (byte() << 8U));
    }
    std::uint32_t u32() {
        const std::uint32_t low = u16();
        return low | (static_cast<std::uint32_t>(u16()) << 16U);
    }
    /// Up to n bytes of the input (fewer at its end).
    std::span<const std::uint8_t> take(std::size_t n) {
        const std::size_t count = std::min(n, size_ - std::min(offset_, size_));
        const std::span<const std::uint8_t> bytes{data_ + offset_, count};
        offset_ += count;
        return bytes;
    }

private:
    const std::uint8_t* data_;
    std::size_t size_;
    std::size_t offset_ = 0;
};

}  // namespace scopekin::fuzz

// The line of the failed check in the report (clang 14 has no std::source_location).
#define require(condition) ::scopekin::fuzz::require_at((condition), __FILE__, __LINE__)
