// decimal_text.hpp — an unsigned integer as decimal text without printf or the heap (the
// bare-metal test runners print through semihosting, which takes C strings only).
#pragma once

#include <cstddef>
#include <cstdint>

namespace scopekin::portable_check {

/// Room for 2^64 - 1 (20 digits) and the terminating NUL.
using DecimalBuffer = char[21];

/// Writes `value` into the end of `buffer` and returns where its text starts.
inline const char* decimal_text(std::uint64_t value, DecimalBuffer& buffer) noexcept {
    std::size_t n = sizeof buffer;
    buffer[--n] = '\0';
    do {
        buffer[--n] = static_cast<char>('0' + static_cast<int>(value % 10U));
        value /= 10U;
    } while (value != 0U && n > 0U);
    return &buffer[n];
}

}  // namespace scopekin::portable_check
