// candump log lines (hal/candump): the formats can-utils writes (`candump -L`), round trips,
// and a refusal with a reason for everything else.
#include <array>
#include <cstring>
#include <string_view>

#include "hal/candump/candump_log.hpp"
#include "portable_check.hpp"

namespace {

namespace hal = scopekin::hal;
using hal::CandumpParse;

std::string_view format(const hal::CandumpRecord& record,
                        std::array<char, hal::kCandumpLineCapacity>& buffer) {
    const std::size_t length = hal::format_candump_line(record, buffer);
    return std::string_view{buffer.data(), length};
}

}  // namespace

SCOPEKIN_TEST(CandumpLog, ParsesTheFormatsCandumpWrites) {
    hal::CandumpRecord record{};
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1700000000.123456) vcan0 110#C40918FC0009\n",
                                                 record) == CandumpParse::ok);
    SCOPEKIN_EXPECT_EQ(record.timestamp_us, 1700000000123456ULL);
    SCOPEKIN_EXPECT_TRUE(std::strcmp(record.interface.data(), "vcan0") == 0);
    SCOPEKIN_EXPECT_EQ(record.frame.id, 0x110U);
    SCOPEKIN_EXPECT_TRUE(!record.frame.extended && !record.frame.error && !record.frame.remote);
    SCOPEKIN_EXPECT_EQ(record.frame.length, 6);
    SCOPEKIN_EXPECT_EQ(record.frame.data[0], 0xC4);
    SCOPEKIN_EXPECT_EQ(record.frame.data[5], 0x09);

    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(0.000001) can1 12345678#DEADBEEF", record) ==
                         CandumpParse::ok);
    SCOPEKIN_EXPECT_TRUE(record.frame.extended);
    SCOPEKIN_EXPECT_EQ(record.frame.id, 0x12345678U);
    SCOPEKIN_EXPECT_EQ(record.frame.length, 4);

    // An 8-digit id with bit 29 (CAN_ERR_FLAG) is an error frame; the rest are its classes.
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) vcan0 20000040#0000000000000000\r\n",
                                                 record) == CandumpParse::ok);
    SCOPEKIN_EXPECT_TRUE(record.frame.error);
    SCOPEKIN_EXPECT_EQ(record.frame.id, static_cast<std::uint32_t>(hal::kCanErrorBusOff));
    SCOPEKIN_EXPECT_EQ(record.frame.length, 8);

    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(2.500000) vcan0 123#R", record) ==
                         CandumpParse::ok);
    SCOPEKIN_EXPECT_TRUE(record.frame.remote);
    SCOPEKIN_EXPECT_EQ(record.frame.length, 0);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(2.500000) vcan0 123#R4", record) ==
                         CandumpParse::ok);
    SCOPEKIN_EXPECT_EQ(record.frame.length, 4);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(2.500000) vcan0 123#", record) ==
                         CandumpParse::ok);
    SCOPEKIN_EXPECT_EQ(record.frame.length, 0);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(2.500000) vcan0 123#11.22.33", record) ==
                         CandumpParse::ok);
    SCOPEKIN_EXPECT_EQ(record.frame.length, 3);
    SCOPEKIN_EXPECT_EQ(record.frame.data[2], 0x33);
}

SCOPEKIN_TEST(CandumpLog, RefusesWithAReason) {
    hal::CandumpRecord record{};
    record.frame.id = 0x42;  // untouched by a refused line
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("   \n", record) == CandumpParse::blank);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("1.000000 vcan0 123#00", record) ==
                         CandumpParse::bad_timestamp);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.0001) vcan0 123#00", record) ==
                         CandumpParse::bad_timestamp);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000 vcan0 123#00", record) ==
                         CandumpParse::bad_timestamp);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000)", record) ==
                         CandumpParse::bad_interface);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) averyveryverylongname 123#00",
                                                 record) == CandumpParse::bad_interface);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) vcan0 1234#00", record) ==
                         CandumpParse::bad_identifier);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) vcan0 800#00", record) ==
                         CandumpParse::bad_identifier);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) vcan0 123456789#00", record) ==
                         CandumpParse::bad_identifier);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) vcan0 123 00", record) ==
                         CandumpParse::bad_identifier);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) vcan0 123#0", record) ==
                         CandumpParse::bad_data);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) vcan0 123#0G", record) ==
                         CandumpParse::bad_data);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) vcan0 123#001122334455667788",
                                                 record) == CandumpParse::bad_data);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) vcan0 123##10011", record) ==
                         CandumpParse::fd_unsupported);
    SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line("(1.000000) vcan0 123#00 extra", record) ==
                         CandumpParse::trailing_garbage);
    SCOPEKIN_EXPECT_EQ(record.frame.id, 0x42U);
    SCOPEKIN_EXPECT_TRUE(std::strlen(hal::describe(CandumpParse::bad_data)) > 10U);
}

SCOPEKIN_TEST(CandumpLog, FormatsWhatItParses) {
    const char* const lines[] = {
        "(1700000000.123456) vcan0 110#C40918FC0009\n",
        "(0.000001) can1 12345678#DEADBEEF\n",
        "(1.000000) vcan0 20000040#0000000000000000\n",
        "(2.500000) vcan0 123#R4\n",
        "(2.500000) vcan0 7FF#\n",
    };
    for (const char* line : lines) {
        hal::CandumpRecord record{};
        SCOPEKIN_EXPECT_TRUE(hal::parse_candump_line(line, record) == CandumpParse::ok);
        std::array<char, hal::kCandumpLineCapacity> buffer{};
        SCOPEKIN_EXPECT_TRUE(format(record, buffer) == std::string_view{line});
    }
    // A buffer that is too small or an invalid frame gives 0, never a partial line.
    hal::CandumpRecord bad{};
    hal::set_candump_interface(bad, "vcan0");
    bad.frame.length = 9;
    std::array<char, hal::kCandumpLineCapacity> buffer{};
    SCOPEKIN_EXPECT_EQ(hal::format_candump_line(bad, buffer), 0U);
    std::array<char, 10> small{};
    bad.frame.length = 1;
    SCOPEKIN_EXPECT_EQ(hal::format_candump_line(bad, small), 0U);
}
