// fuzz_candump_parser.cpp — libFuzzer target: hal::parse_candump_line (hal/candump/candump_log.hpp)
// on any line, as scopekin-box's replay and the host tools read logs someone else wrote.
//
// Oracles (__builtin_trap() on violation, on top of ASan/UBSan):
//   * a refusal leaves the record untouched;
//   * ok: the record is a frame format_candump_line can write (it must write it), and parsing
//     that line again gives exactly the same record (timestamp, interface, id, flags, length,
//     all 8 data bytes); formatting that record again gives the same line.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

#include "hal/candump/candump_log.hpp"

namespace {

using scopekin::hal::CandumpParse;
using scopekin::hal::CandumpRecord;

void require(bool condition) {
    if (!condition) {
        __builtin_trap();
    }
}

bool same(const CandumpRecord& a, const CandumpRecord& b) {
    return a.timestamp_us == b.timestamp_us && a.interface == b.interface &&
           a.frame.id == b.frame.id && a.frame.extended == b.frame.extended &&
           a.frame.remote == b.frame.remote && a.frame.error == b.frame.error &&
           a.frame.length == b.frame.length && a.frame.data == b.frame.data;
}

CandumpRecord sentinel() {
    CandumpRecord record{};
    record.timestamp_us = 0xDEADBEEFU;
    scopekin::hal::set_candump_interface(record, "sentinel0");
    record.frame.id = 0x7AB;
    record.frame.length = 3;
    record.frame.data = {1, 2, 3, 0, 0, 0, 0, 0};
    return record;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // string_view over the fuzzer's own buffer: any read past `size` is an ASan report.
    const std::string_view line{reinterpret_cast<const char*>(data), size};
    CandumpRecord record = sentinel();
    const CandumpParse result = scopekin::hal::parse_candump_line(line, record);
    require(scopekin::hal::describe(result) != nullptr);
    if (result != CandumpParse::ok) {
        require(same(record, sentinel()));
        return 0;
    }

    std::array<char, scopekin::hal::kCandumpLineCapacity> text{};
    const std::size_t length = scopekin::hal::format_candump_line(record, text);
    require(length > 0U && length <= text.size());
    require(text[length - 1U] == '\n');

    CandumpRecord again = sentinel();
    require(scopekin::hal::parse_candump_line(std::string_view{text.data(), length}, again) ==
            CandumpParse::ok);
    require(same(again, record));

    std::array<char, scopekin::hal::kCandumpLineCapacity> text_again{};
    const std::size_t length_again = scopekin::hal::format_candump_line(again, text_again);
    require(length_again == length && std::memcmp(text.data(), text_again.data(), length) == 0);
    return 0;
}
