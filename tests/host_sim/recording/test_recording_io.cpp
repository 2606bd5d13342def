// The recording CSV: header, writer, strict reader (every error with its exact line number and
// column), extra columns, gaps.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "host_sim/recording/recording_format.hpp"
#include "host_sim/recording/recording_reader.hpp"

namespace {

using scopekin::recording::EmPoseCells;
using scopekin::recording::ForceTorqueCells;
using scopekin::recording::InsertionRollCells;
using scopekin::recording::Recording;
using scopekin::recording::RecordingError;
using scopekin::recording::RecordingGap;
using scopekin::recording::RecordingReader;
using scopekin::recording::RecordingReaderOptions;
using scopekin::recording::RecordingRow;
using scopekin::recording::RecordingWriter;
using scopekin::recording::TipForceCells;

const std::string kHeader =
    "time_s,handle_force_N,handle_torque_Nmm,insertion_mm,roll_rad,"
    "em_tip_x_mm,em_tip_y_mm,em_tip_z_mm,em_tip_qw,em_tip_qx,em_tip_qy,em_tip_qz,"
    "em_20cm_x_mm,em_20cm_y_mm,em_20cm_z_mm,em_20cm_qw,em_20cm_qx,em_20cm_qy,em_20cm_qz,"
    "em_handle_x_mm,em_handle_y_mm,em_handle_z_mm,em_handle_qw,em_handle_qx,em_handle_qy,em_handle_"
    "qz,"
    "em_sigmoid_x_mm,em_sigmoid_y_mm,em_sigmoid_z_mm,em_sigmoid_qw,em_sigmoid_qx,em_sigmoid_qy,em_"
    "sigmoid_qz,"
    "tip_force_x_N,tip_force_y_N,tip_force_z_N,region";

/// A data line: time, force, torque, insertion, roll, 28 empty EM cells, 3 tip force cells, region.
std::string line(const std::string& time, const std::string& force = "1.000",
                 const std::string& torque = "2.0", const std::string& insertion = "100.00",
                 const std::string& roll = "0.1000", const std::string& tip = ",,",
                 const std::string& region = "rectum") {
    return time + "," + force + "," + torque + "," + insertion + "," + roll + std::string(28, ',') +
           "," + tip + "," + region;
}

Recording read(const std::string& text, RecordingReader reader = RecordingReader()) {
    std::istringstream in(text);
    return reader.read(in);
}

/// The RecordingError of reading `text`, or fails.
RecordingError error_of(const std::string& text) {
    try {
        (void)read(text);
    } catch (const RecordingError& e) {
        return e;
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return RecordingError("", 0);
}

TEST(RecordingSchema, HeaderIsTheDocumentedColumns) {
    EXPECT_EQ(scopekin::recording::recording_header(), kHeader);
    EXPECT_EQ(scopekin::recording::recording_columns().size(), 37u);
}

TEST(RecordingReader, ReadsRowsGroupsAndRegion) {
    const std::string text =
        kHeader + "\n" + line("0.000000") + "\n" + line("0.001000", "", "", "", "", ",,", "") +
        "\n" +
        line("0.002500", "-3.250", "-7.5", "12.34", "-0.0001", "0.000,0.000,1.234", "sigmoid") +
        "\n";
    const Recording r = read(text);
    ASSERT_EQ(r.rows.size(), 3u);
    EXPECT_EQ(r.rows[0].time_us, 0);
    ASSERT_TRUE(r.rows[0].handle.has_value());
    EXPECT_DOUBLE_EQ(r.rows[0].handle->force_N, 1.0);
    EXPECT_DOUBLE_EQ(r.rows[0].handle->torque_Nmm, 2.0);
    EXPECT_EQ(r.rows[0].region, "rectum");
    EXPECT_FALSE(r.rows[1].has_sensor_data());
    EXPECT_EQ(r.rows[1].region, "");
    EXPECT_EQ(r.rows[2].time_us, 2500);
    EXPECT_DOUBLE_EQ(r.rows[2].insertion_roll->roll_rad, -0.0001);
    ASSERT_TRUE(r.rows[2].tip_force.has_value());
    EXPECT_DOUBLE_EQ(r.rows[2].tip_force->force_N[2], 1.234);
    EXPECT_EQ(r.row_lines, (std::vector<std::size_t>{2, 3, 4}));
    for (const auto& pose : r.rows[2].em)
        EXPECT_FALSE(pose.has_value());
}

TEST(RecordingReader, AcceptsColumnsInAnyOrderAndCrLf) {
    // Swap two columns in the header and in the row.
    std::string header = kHeader;
    header.replace(header.find("handle_force_N,handle_torque_Nmm"), 32,
                   "handle_torque_Nmm,handle_force_N");
    const Recording r = read(header + "\r\n" + line("1.5", "2.0", "1.000") + "\r\n");
    ASSERT_EQ(r.rows.size(), 1u);
    EXPECT_EQ(r.rows[0].time_us, 1'500'000);
    EXPECT_DOUBLE_EQ(r.rows[0].handle->force_N, 1.0);
    EXPECT_DOUBLE_EQ(r.rows[0].handle->torque_Nmm, 2.0);
}

TEST(RecordingReader, MissingColumnIsNamedOnLine1) {
    std::string header = kHeader;
    header.erase(header.find(",roll_rad"), 9);
    const RecordingError e = error_of(header + "\n");
    EXPECT_EQ(e.line(), 1u);
    EXPECT_EQ(std::string(e.what()), "line 1: missing column 'roll_rad'");
}

TEST(RecordingReader, UnknownColumnRejectedUnlessItStartsWithX) {
    const RecordingError e = error_of(kHeader + ",comment\n");
    EXPECT_EQ(e.line(), 1u);
    EXPECT_NE(std::string(e.what()).find("unknown column 'comment'"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("'x_'"), std::string::npos) << e.what();

    const Recording r = read(kHeader + ",x_note,x_truth_tip_x_mm\n" + line("0") + ",hello,12.5\n" +
                             line("0.5") + ",,\n");
    EXPECT_EQ(r.extra_columns, (std::vector<std::string>{"x_note", "x_truth_tip_x_mm"}));
    ASSERT_EQ(r.extra_cells.size(), 2u);
    EXPECT_EQ(r.extra_cells[0], (std::vector<std::string>{"hello", "12.5"}));
    EXPECT_EQ(r.extra_cells[1], (std::vector<std::string>{"", ""}));
}

TEST(RecordingReader, AQuoteOrCarriageReturnInAnExtraCellIsRefusedAsTheWriterRefusesIt) {
    // The writer refuses them (the file is not quoted CSV), so the reader does too: every
    // recording it accepts can be written back.
    RecordingError e = error_of(kHeader + ",x_note\n" + line("0") + ",say \"hi\"\n");
    EXPECT_EQ(e.line(), 2u);
    EXPECT_EQ(std::string(e.what()),
              "line 2, column x_note: 'say \"hi\"' holds a quote or a carriage return (not "
              "allowed in a recording's cells)");
    e = error_of(kHeader + ",x_note\n" + line("0") + ",a\rb\r\n");
    EXPECT_EQ(e.line(), 2u);
    EXPECT_EQ(std::string(e.what()),
              "line 2, column x_note: 'a\\x0Db' holds a quote or a carriage return (not allowed in "
              "a recording's cells)");
    e = error_of(kHeader + ",x_\"q\"\n");
    EXPECT_EQ(e.line(), 1u);
    EXPECT_EQ(std::string(e.what()),
              "line 1: extra column 'x_\"q\"' holds a quote or a carriage return (not allowed in "
              "a recording's cells)");
    // A trailing CR is the line end (CRLF), not part of the cell.
    const Recording r = read(kHeader + ",x_note\r\n" + line("0") + ",ok\r\n");
    EXPECT_EQ(r.extra_cells[0][0], "ok");
}

TEST(RecordingReader, DuplicateColumnRejected) {
    const RecordingError e = error_of(kHeader + ",region\n");
    EXPECT_EQ(e.line(), 1u);
    EXPECT_EQ(std::string(e.what()), "line 1: column 'region' appears twice");
}

TEST(RecordingReader, UnsortedTimeNamesBothLines) {
    const RecordingError e = error_of(kHeader + "\n" + line("0.001") + "\n" + line("0.003") + "\n" +
                                      line("0.002") + "\n");
    EXPECT_EQ(e.line(), 4u);
    EXPECT_EQ(std::string(e.what()), "line 4: time_s 0.002 is not later than line 3's 0.003");
}

TEST(RecordingReader, DuplicateTimeNamesBothLines) {
    const RecordingError e =
        error_of(kHeader + "\n" + line("1.234") + "\n" + line("1.234000") + "\n");
    EXPECT_EQ(e.line(), 3u);
    EXPECT_EQ(std::string(e.what()), "line 3: time_s 1.234000 is not later than line 2's 1.234");
}

TEST(RecordingReader, NonNumericCellNamesLineAndColumn) {
    const RecordingError e =
        error_of(kHeader + "\n" + line("0") + "\n" + line("0.001", "abc") + "\n");
    EXPECT_EQ(e.line(), 3u);
    EXPECT_EQ(std::string(e.what()), "line 3, column handle_force_N: 'abc' is not a number");
    // Leading blanks, trailing text, infinities are no numbers either.
    EXPECT_EQ(std::string(error_of(kHeader + "\n" + line("0", " 1.0") + "\n").what()),
              "line 2, column handle_force_N: ' 1.0' is not a number");
    EXPECT_EQ(std::string(error_of(kHeader + "\n" + line("0", "1.0N") + "\n").what()),
              "line 2, column handle_force_N: '1.0N' is not a number");
    EXPECT_EQ(std::string(error_of(kHeader + "\n" + line("0", "inf") + "\n").what()),
              "line 2, column handle_force_N: 'inf' is not a finite number");
    EXPECT_EQ(std::string(error_of(kHeader + "\n" + line("x") + "\n").what()),
              "line 2, column time_s: 'x' is not a number");
}

TEST(RecordingReader, TimeMustBePlainSecondsWithAtMostSixDecimals) {
    const RecordingError e1 = error_of(kHeader + "\n" + line("0.0000001") + "\n");
    EXPECT_EQ(e1.line(), 2u);
    EXPECT_NE(std::string(e1.what()).find("more than 6 decimals"), std::string::npos) << e1.what();
    const RecordingError e2 = error_of(kHeader + "\n" + line("-1") + "\n");
    EXPECT_NE(std::string(e2.what()).find("'-1' is negative"), std::string::npos) << e2.what();
    const RecordingError e3 = error_of(kHeader + "\n" + line("1e-3") + "\n");
    EXPECT_NE(std::string(e3.what()).find("plain seconds"), std::string::npos) << e3.what();
    EXPECT_EQ(read(kHeader + "\n" + line("12") + "\n" + line("12.000001") + "\n").rows[1].time_us,
              12'000'001);
}

TEST(RecordingReader, PartialGroupNamesLineAndTheEmptyCell) {
    const RecordingError e = error_of(kHeader + "\n" + line("0") + "\n" + line("0.001") + "\n" +
                                      line("0.002", "1.0", "") + "\n");
    EXPECT_EQ(e.line(), 4u);
    EXPECT_NE(
        std::string(e.what()).find("line 4, column handle_torque_Nmm: empty, but handle_force_N"),
        std::string::npos)
        << e.what();
    // An EM sensor with 6 of its 7 cells.
    std::string row = line("0");
    const std::size_t em_start = row.find(",,");  // after roll: the 28 EM cells begin
    row.replace(em_start, 7, ",1,2,3,1,0,0,");    // em_tip x..qy filled, qz empty
    const RecordingError em = error_of(kHeader + "\n" + row + "\n");
    EXPECT_EQ(em.line(), 2u);
    EXPECT_NE(std::string(em.what()).find("column em_tip_qz: empty, but em_tip_x_mm"),
              std::string::npos)
        << em.what();
    // Tip force with one of three.
    const RecordingError tip =
        error_of(kHeader + "\n" + line("0", "1.0", "1.0", "1.0", "0", ",,2.0") + "\n");
    EXPECT_NE(std::string(tip.what()).find("column tip_force_x_N: empty, but tip_force_z_N"),
              std::string::npos)
        << tip.what();
}

TEST(RecordingReader, RangesRegionCellCountAndEmptyLines) {
    auto message = [](const std::string& text) { return std::string(error_of(text).what()); };
    EXPECT_EQ(message(kHeader + "\n" + line("0", "1", "1", "2600") + "\n"),
              "line 2, column insertion_mm: 2600 is outside the plausible range [-50, 2500]");
    EXPECT_EQ(
        message(kHeader + "\n" + line("0", "200") + "\n"),
        "line 2, column handle_force_N: 200 is outside the plausible range [-163.84, 163.835]");
    EXPECT_EQ(message(kHeader + "\n" + line("0", "1", "1", "1", "1", "30,0,0") + "\n"),
              "line 2, column tip_force_x_N: 30 is outside the plausible range [-25, 25]");
    EXPECT_NE(message(kHeader + "\n" + line("0", "1", "1", "1", "1", ",,", "colon") + "\n")
                  .find("line 2, column region: 'colon' is not a colon region (rectum, sigmoid"),
              std::string::npos);
    EXPECT_EQ(message(kHeader + "\n" + line("0") + ",extra\n"),
              "line 2: 38 cells, the header has 37 columns");
    EXPECT_EQ(message(kHeader + "\n" + line("0") + "\n\n" + line("1") + "\n"),
              "line 3: empty line (every line after the header is a row)");
    EXPECT_EQ(message(""), "line 1: the file is empty (expected the header)");
    // A quaternion that is not unit.
    std::string row = line("0");
    row.replace(row.find(",,"), 8, ",1,2,3,0.99,0,0,0,");
    const std::string norm = message(kHeader + "\n" + row + "\n");
    EXPECT_EQ(norm.rfind("line 2, column em_tip_qw: the quaternion's norm 0.9", 0), 0u) << norm;
    EXPECT_NE(norm.find("is not 1 (tolerance 0.001)"), std::string::npos) << norm;
}

TEST(RecordingReader, ReadFileNamesTheFile) {
    const std::string path = ::testing::TempDir() + "scopekin_recording_bad.csv";
    {
        std::ofstream out(path);
        out << kHeader << "\n" << line("0", "abc") << "\n";
    }
    try {
        (void)RecordingReader().read_file(path);
        FAIL() << "no error";
    } catch (const RecordingError& e) {
        EXPECT_EQ(std::string(e.what()),
                  path + ": line 2, column handle_force_N: 'abc' is not a number");
        EXPECT_EQ(e.line(), 2u);
    }
    std::remove(path.c_str());
    EXPECT_THROW((void)RecordingReader().read_file(path), RecordingError);
}

TEST(RecordingReader, AByteOrderMarkBeforeTheHeaderIsSkipped) {
    const Recording r = read("\xEF\xBB\xBF" + kHeader + "\n" + line("0") + "\n");
    ASSERT_EQ(r.rows.size(), 1u);
    EXPECT_EQ(r.rows[0].time_us, 0);
}

TEST(RecordingReader, NumbersBeyondDoubleAreOutOfRange) {
    EXPECT_EQ(std::string(error_of(kHeader + "\n" + line("0", "1e309") + "\n").what()),
              "line 2, column handle_force_N: '1e309' is out of range (a number's magnitude must "
              "be below 1.8e308)");
    EXPECT_EQ(std::string(error_of(kHeader + "\n" + line("0", "1", "-1e400") + "\n").what()),
              "line 2, column handle_torque_Nmm: '-1e400' is out of range (a number's magnitude "
              "must be below 1.8e308)");
    // An underflow is zero, as the JSON readers have it.
    EXPECT_EQ(read(kHeader + "\n" + line("0", "1e-400") + "\n").rows[0].handle->force_N, 0.0);
}

TEST(RecordingReader, LongCellsAndNamesAreQuotedBounded) {
    const std::string huge(20 * 1024 * 1024, 'x');
    const std::string message = error_of(kHeader + "\n" + line("0", huge) + "\n").what();
    EXPECT_EQ(message, "line 2, column handle_force_N: '" + std::string(80, 'x') +
                           "…' (20971520 bytes) is not a number");
    // 20 million digits: a number, far beyond double.
    const std::string digits =
        error_of(kHeader + "\n" + line("0", std::string(huge.size(), '7')) + "\n").what();
    EXPECT_EQ(digits, "line 2, column handle_force_N: '" + std::string(80, '7') +
                          "…' (20971520 bytes) is out of range (a number's magnitude must be "
                          "below 1.8e308)");
    const std::string name(100000, 'c');
    const std::string header = error_of(kHeader + "," + name + "\n").what();
    EXPECT_EQ(header, "line 1: unknown column '" + std::string(80, 'c') +
                          "…' (100000 bytes) (extra columns are allowed only with a name starting "
                          "with 'x_')");
    const std::string region =
        error_of(kHeader + "\n" + line("0", "1", "1", "1", "1", ",,", std::string(500, 'r')) + "\n")
            .what();
    EXPECT_EQ(region.rfind("line 2, column region: '" + std::string(80, 'r') +
                               "…' (500 bytes) is "
                               "not a colon region",
                           0),
              0u)
        << region;
}

TEST(RecordingReader, AGapBetweenRowsLongerThanTheBoundIsRefusedWithItsLine) {
    // 60 s by default: a row 60.000001 s after the one before is refused, 60 s exactly is not.
    EXPECT_EQ(
        std::string(error_of(kHeader + "\n" + line("1") + "\n" + line("61.000001") + "\n").what()),
        "line 3: time_s 61.000001 is 60.000001 s after line 2's 1: a gap between rows "
        "longer than 60 s is refused (a run would step across all of it; --max-gap-s raises the "
        "bound)");
    EXPECT_EQ(read(kHeader + "\n" + line("1") + "\n" + line("61") + "\n").rows.size(), 2u);
    // A row 10^9 s later, and the bound raised.
    const std::string far = kHeader + "\n" + line("0") + "\n" + line("999999999") + "\n";
    EXPECT_EQ(error_of(far).line(), 3u);
    RecordingReaderOptions wide;
    wide.max_gap_s = 1e9;
    EXPECT_EQ(read(far, RecordingReader(wide)).rows.size(), 2u);
    // The first row may be late: the bound is between rows.
    EXPECT_EQ(read(kHeader + "\n" + line("5000") + "\n").rows.size(), 1u);
    // The bound must be positive and finite.
    for (const double bad : {0.0, -1.0, std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::quiet_NaN()}) {
        RecordingReaderOptions o;
        o.max_gap_s = bad;
        EXPECT_THROW(RecordingReader{o}, RecordingError) << bad;
    }
}

/// Rows every 1 ms from 0 to `end_ms`, force/torque except in [a, b) ms, insertion/roll except in [c, d) ms.
std::vector<RecordingRow> rows_with_silences(int end_ms, int a, int b, int c, int d) {
    std::vector<RecordingRow> rows;
    for (int ms = 0; ms <= end_ms; ++ms) {
        RecordingRow row;
        row.time_us = ms * 1000;
        if (ms < a || ms >= b) row.handle = ForceTorqueCells{1.0, 0.0};
        if (ms < c || ms >= d) row.insertion_roll = InsertionRollCells{10.0, 0.0};
        rows.push_back(row);
    }
    return rows;
}

TEST(RecordingGaps, SilencesLongerThanTheThresholdAreFound) {
    // Force silent from 100 to 160 ms: last sample 99, next 160 -> 61 ms > 50 ms.
    // Insertion silent from 300 to 350 ms: last 299, next 350 -> 51 ms > 50 ms.
    const auto gaps =
        scopekin::recording::find_gaps(rows_with_silences(1000, 100, 160, 300, 350), 0.05);
    ASSERT_EQ(gaps.size(), 2u);
    EXPECT_EQ(gaps[0], (RecordingGap{0.099, 0.160, "handle_force_torque"}));
    EXPECT_EQ(gaps[1], (RecordingGap{0.299, 0.350, "insertion_roll"}));
    EXPECT_NEAR(gaps[0].duration_s(), 0.061, 1e-12);
}

TEST(RecordingGaps, ExactlyTheThresholdIsNoGap) {
    // 99 -> 149: 50 ms, not longer than 50 ms.
    EXPECT_TRUE(
        scopekin::recording::find_gaps(rows_with_silences(500, 100, 149, 0, 0), 0.05).empty());
    EXPECT_EQ(scopekin::recording::find_gaps(rows_with_silences(500, 100, 150, 0, 0), 0.05).size(),
              1u);
}

TEST(RecordingGaps, LeadingTrailingAndNeverDelivered) {
    // Force starts only at 80 ms and stops after 900 ms of a 1 s recording; insertion never comes.
    std::vector<RecordingRow> rows = rows_with_silences(1000, 0, 80, 0, 1001);
    for (auto& row : rows)
        if (row.time_us > 900'000) row.handle.reset();
    const auto gaps = scopekin::recording::find_gaps(rows, 0.05);
    ASSERT_EQ(gaps.size(), 3u);
    EXPECT_EQ(gaps[0], (RecordingGap{0.0, 0.080, "handle_force_torque"}));
    EXPECT_EQ(gaps[1], (RecordingGap{0.900, 1.0, "handle_force_torque"}));
    EXPECT_EQ(gaps[2], (RecordingGap{0.0, 1.0, "insertion_roll"}));
}

TEST(RecordingGaps, TheReaderReportsThemWithItsThreshold) {
    std::ostringstream out;
    {
        RecordingWriter writer(out);
        for (const auto& row : rows_with_silences(300, 100, 125, 0, 0))
            writer.write(row);
    }
    EXPECT_TRUE(read(out.str()).gaps.empty());  // 26 ms
    const auto r = read(out.str(), RecordingReader({0.02}));
    ASSERT_EQ(r.gaps.size(), 1u);
    EXPECT_EQ(r.gaps[0], (RecordingGap{0.099, 0.125, "handle_force_torque"}));
    EXPECT_THROW((void)RecordingReader({0.0}), RecordingError);
}

TEST(RecordingWriter, RefusesWhatTheReaderWouldReject) {
    std::ostringstream out;
    RecordingWriter writer(out, {"x_note"});
    RecordingRow row;
    row.time_us = 5000;
    row.handle = ForceTorqueCells{1.0, 1.0};
    writer.write(row, {"first"});
    try {
        writer.write(row);
        FAIL() << "duplicate time accepted";
    } catch (const RecordingError& e) {
        EXPECT_EQ(e.line(), 3u);
        EXPECT_EQ(std::string(e.what()),
                  "line 3: time_s 0.005000 is not later than line 2's 0.005000");
    }
    row.time_us = 6000;
    row.handle->force_N = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(writer.write(row), RecordingError);
    row.handle->force_N = 500.0;
    try {
        writer.write(row);
        FAIL() << "500 N accepted";
    } catch (const RecordingError& e) {
        EXPECT_EQ(
            std::string(e.what()),
            "line 3, column handle_force_N: 500 is outside the plausible range [-163.84, 163.835]");
    }
    row.handle.reset();
    row.region = "stomach";
    EXPECT_THROW(writer.write(row), RecordingError);
    row.region = "cecum";
    EXPECT_THROW(writer.write(row, {"a,b"}), RecordingError);
    writer.write(row, {"second"});
    EXPECT_EQ(writer.rows_written(), 2u);
    EXPECT_THROW(RecordingWriter(out, {"note"}), RecordingError);
    EXPECT_THROW(RecordingWriter(out, {"x_a", "x_a"}), RecordingError);

    const Recording r = read(out.str().substr(out.str().find("time_s")));
    ASSERT_EQ(r.rows.size(), 2u);
    EXPECT_EQ(r.rows[1].region, "cecum");
    EXPECT_EQ(r.extra_cells[0][0], "first");
    EXPECT_EQ(r.extra_cells[1][0], "second");
}

TEST(RecordingWriter, WritesEveryGroupAtItsResolution) {
    RecordingRow row;
    row.time_us = 1'000'250;
    row.handle = ForceTorqueCells{1.23456, -7.06};
    row.insertion_roll = InsertionRollCells{250.123, 1.23456789};
    row.em[2] =
        EmPoseCells{{12.3456, -6.7894, 250.0}, {0.7071067811865476, 0.0, 0.0, 0.7071067811865476}};
    row.tip_force = TipForceCells{{-0.15, 0.04, 2.5}};
    row.region = "descending";
    const std::string text = scopekin::recording::format_recording_row(row);
    EXPECT_EQ(text, "1.000250,1.235,-7.1,250.12,1.2346" + std::string(14, ',') +
                        ",12.346,-6.789,250.000,0.707092,0.000000,0.000000,0.707092" +
                        std::string(7, ',') + ",-0.150,0.040,2.500,descending");
}

}  // namespace
