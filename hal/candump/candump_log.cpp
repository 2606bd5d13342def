// candump_log.cpp — see candump_log.hpp.
#include "hal/candump/candump_log.hpp"

namespace scopekin::hal {

namespace {

constexpr std::uint32_t kCanErrorFlag = 0x20000000U;  // CAN_ERR_FLAG of linux/can.h

int hex_value(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    return -1;
}

bool is_blank(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

/// Reads `count` decimal digits at `text[pos]` into `value` (count <= 19: no overflow at 10^19 -
/// we allow at most 12 here).
bool read_decimal(std::string_view text, std::size_t& pos, std::size_t max_digits,
                  std::uint64_t& value, std::size_t& digits) {
    value = 0;
    digits = 0;
    while (pos < text.size() && text[pos] >= '0' && text[pos] <= '9') {  // bound: max_digits
        if (digits == max_digits) {
            return false;
        }
        value = value * 10U + static_cast<std::uint64_t>(text[pos] - '0');
        ++digits;
        ++pos;
    }
    return digits > 0;
}

constexpr char kHexDigits[] = "0123456789ABCDEF";

void put_hex(std::span<char> out, std::size_t& pos, std::uint32_t value, int digits) {
    for (int k = digits - 1; k >= 0; --k) {  // bound: 8
        out[pos++] = kHexDigits[(value >> (4 * k)) & 0xFU];
    }
}

}  // namespace

const char* describe(CandumpParse result) {
    switch (result) {
        case CandumpParse::ok: return "ok";
        case CandumpParse::blank: return "blank line";
        case CandumpParse::bad_timestamp:
            return "bad timestamp: expected (seconds.microseconds) with 6 digits of microseconds";
        case CandumpParse::bad_interface:
            return "bad interface name: expected 1 to 15 characters after the timestamp";
        case CandumpParse::bad_identifier:
            return "bad identifier: expected 3 hex digits (11-bit) or 8 hex digits (29-bit / error "
                   "frame) before '#'";
        case CandumpParse::bad_data:
            return "bad data: expected up to 8 bytes as pairs of hex digits after '#', or R for a "
                   "remote frame";
        case CandumpParse::fd_unsupported:
            return "CAN FD frame ('##'): not supported, the box uses classic CAN";
        case CandumpParse::trailing_garbage: return "unexpected text after the frame";
    }
    return "unknown";
}

CandumpParse parse_candump_line(std::string_view line, CandumpRecord& record) {
    std::size_t pos = 0;
    while (pos < line.size() && is_blank(line[pos]))
        ++pos;  // bound: line.size()
    if (pos == line.size()) {
        return CandumpParse::blank;
    }
    CandumpRecord parsed{};

    // (seconds.microseconds)
    if (line[pos] != '(') return CandumpParse::bad_timestamp;
    ++pos;
    std::uint64_t seconds = 0;
    std::uint64_t micros = 0;
    std::size_t digits = 0;
    if (!read_decimal(line, pos, 12, seconds, digits)) return CandumpParse::bad_timestamp;
    if (pos >= line.size() || line[pos] != '.') return CandumpParse::bad_timestamp;
    ++pos;
    if (!read_decimal(line, pos, 6, micros, digits) || digits != 6)
        return CandumpParse::bad_timestamp;
    if (pos >= line.size() || line[pos] != ')') return CandumpParse::bad_timestamp;
    ++pos;
    parsed.timestamp_us = seconds * 1000000U + micros;

    // interface
    if (pos >= line.size() || line[pos] != ' ') return CandumpParse::bad_interface;
    while (pos < line.size() && line[pos] == ' ')
        ++pos;  // bound: line.size()
    std::size_t name_length = 0;
    while (pos < line.size() && !is_blank(line[pos])) {  // bound: line.size()
        if (name_length == kCandumpInterfaceCapacity - 1U || line[pos] == '\0') {
            return CandumpParse::bad_interface;  // too long, or a NUL that would cut the name
        }
        parsed.interface[name_length++] = line[pos++];
    }
    if (name_length == 0) return CandumpParse::bad_interface;
    while (pos < line.size() && line[pos] == ' ')
        ++pos;  // bound: line.size()

    // identifier
    const std::size_t id_start = pos;
    std::uint32_t id = 0;
    while (pos < line.size() && hex_value(line[pos]) >= 0) {  // bound: 9 digits, then refused
        if (pos - id_start == 8) return CandumpParse::bad_identifier;
        id = (id << 4U) | static_cast<std::uint32_t>(hex_value(line[pos]));
        ++pos;
    }
    const std::size_t id_digits = pos - id_start;
    if (pos >= line.size() || line[pos] != '#') return CandumpParse::bad_identifier;
    if (id_digits == 3) {
        if (id > kCanStandardIdMask) return CandumpParse::bad_identifier;
        parsed.frame.id = id;
    } else if (id_digits == 8) {
        if ((id & kCanErrorFlag) != 0U) {
            parsed.frame.error = true;
            parsed.frame.id = id & kCanExtendedIdMask;  // error classes
        } else {
            if (id > kCanExtendedIdMask) return CandumpParse::bad_identifier;  // RTR/EFF bits
            parsed.frame.extended = true;
            parsed.frame.id = id;
        }
    } else {
        return CandumpParse::bad_identifier;
    }
    ++pos;  // '#'
    if (pos < line.size() && line[pos] == '#') return CandumpParse::fd_unsupported;

    // data or remote
    if (pos < line.size() && (line[pos] == 'R' || line[pos] == 'r')) {
        if (parsed.frame.error) return CandumpParse::bad_data;
        ++pos;
        parsed.frame.remote = true;
        if (pos < line.size() && line[pos] >= '0' && line[pos] <= '8') {
            parsed.frame.length = static_cast<std::uint8_t>(line[pos] - '0');
            ++pos;
        }
    } else {
        std::uint8_t length = 0;
        while (pos < line.size() && !is_blank(line[pos])) {  // bound: 8 bytes, then refused
            if (line[pos] == '.') {
                ++pos;
                continue;
            }
            if (length == kCanMaxLength || pos + 1 >= line.size()) return CandumpParse::bad_data;
            const int high = hex_value(line[pos]);
            const int low = hex_value(line[pos + 1]);
            if (high < 0 || low < 0) return CandumpParse::bad_data;
            parsed.frame.data[length++] = static_cast<std::uint8_t>((high << 4) | low);
            pos += 2;
        }
        parsed.frame.length = length;
    }
    while (pos < line.size() && is_blank(line[pos]))
        ++pos;  // bound: line.size()
    if (pos != line.size()) return CandumpParse::trailing_garbage;
    record = parsed;
    return CandumpParse::ok;
}

std::size_t format_candump_line(const CandumpRecord& record, std::span<char> out) {
    const CanFrame& frame = record.frame;
    if (!is_valid_can_frame(frame) || record.interface[0] == '\0' ||
        out.size() < kCandumpLineCapacity) {
        return 0;
    }
    std::size_t pos = 0;
    out[pos++] = '(';
    // seconds: up to 20 digits, written into a scratch buffer in reverse
    std::uint64_t seconds = record.timestamp_us / 1000000U;
    const auto micros = static_cast<std::uint32_t>(record.timestamp_us % 1000000U);
    std::array<char, 20> reversed{};
    std::size_t n = 0;
    do {
        reversed[n++] = static_cast<char>('0' + seconds % 10U);
        seconds /= 10U;
    } while (seconds != 0U && n < reversed.size());
    while (n > 0)
        out[pos++] = reversed[--n];  // bound: 20
    out[pos++] = '.';
    std::uint32_t divisor = 100000;
    for (int k = 0; k < 6; ++k) {  // bound: 6
        out[pos++] = static_cast<char>('0' + (micros / divisor) % 10U);
        divisor /= 10U;
    }
    out[pos++] = ')';
    out[pos++] = ' ';
    for (std::size_t k = 0; k + 1 < kCandumpInterfaceCapacity && record.interface[k] != '\0'; ++k) {
        out[pos++] = record.interface[k];
    }
    out[pos++] = ' ';
    if (frame.error) {
        put_hex(out, pos, (frame.id & kCanExtendedIdMask) | kCanErrorFlag, 8);
    } else if (frame.extended) {
        put_hex(out, pos, frame.id, 8);
    } else {
        put_hex(out, pos, frame.id, 3);
    }
    out[pos++] = '#';
    if (frame.remote) {
        out[pos++] = 'R';
        if (frame.length > 0U) out[pos++] = static_cast<char>('0' + frame.length);
    } else {
        for (std::size_t k = 0; k < frame.length; ++k) {  // bound: 8
            put_hex(out, pos, frame.data[k], 2);
        }
    }
    out[pos++] = '\n';
    return pos;
}

void set_candump_interface(CandumpRecord& record, std::string_view name) {
    record.interface = {};
    for (std::size_t k = 0; k < name.size() && k + 1 < kCandumpInterfaceCapacity; ++k) {
        record.interface[k] = name[k];
    }
}

}  // namespace scopekin::hal
