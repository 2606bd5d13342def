// candump_log.hpp — the candump log format of can-utils (`candump -L`, read by `canplayer`):
//
//   (1700000000.123456) vcan0 110#D00700000002
//   (1700000000.123789) vcan0 12345678#DEADBEEF      29-bit id: 8 hex digits
//   (1700000000.124000) vcan0 20000040#0000000000000000   8 digits with bit 29 set: error frame
//   (1700000000.124100) vcan0 123#R                  remote frame (optional length digit: 123#R4)
//
// Timestamp: seconds '.' exactly 6 digits of microseconds.  Interface: 1..15 characters without
// blanks.  Identifier: 3 hex digits (11-bit) or 8 hex digits (29-bit, or an error frame when bit
// 29 = CAN_ERR_FLAG is set, as can-utils' lib.c parses it).  Data: 0..8 bytes as hex pairs, '.'
// allowed between bytes.  CAN FD frames (`##`) are refused, as this box speaks classic CAN.
// A trailing '\r' or blanks are ignored.  Anything else is refused with the reason: never a
// crash on any input (fuzzed: tests/fuzz).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "hal/can_bus.hpp"

namespace scopekin::hal {

inline constexpr std::size_t kCandumpInterfaceCapacity = 16;  ///< IFNAMSIZ, with the NUL
/// Longest line format_candump_line writes (error frame, 8 bytes, 15-char interface): 60 chars.
inline constexpr std::size_t kCandumpLineCapacity = 96;

struct CandumpRecord {
    std::uint64_t timestamp_us{0};
    std::array<char, kCandumpInterfaceCapacity> interface {};  ///< NUL-terminated
    CanFrame frame{};
};

enum class CandumpParse : std::uint8_t {
    ok,
    blank,  ///< empty line (or only blanks): nothing to replay, not an error
    bad_timestamp,
    bad_interface,
    bad_identifier,
    bad_data,
    fd_unsupported,
    trailing_garbage,
};

[[nodiscard]] const char* describe(CandumpParse result);

/// Parses one line (without or with its '\n').
[[nodiscard]] CandumpParse parse_candump_line(std::string_view line, CandumpRecord& record);

/// Writes `record` as one line with '\n' into `out`; returns the length, or 0 if `out` is too
/// small or the record cannot be written (frame invalid, interface empty).
[[nodiscard]] std::size_t format_candump_line(const CandumpRecord& record, std::span<char> out);

/// Copies `name` (truncated to 15 characters) into a record's interface field.
void set_candump_interface(CandumpRecord& record, std::string_view name);

}  // namespace scopekin::hal
