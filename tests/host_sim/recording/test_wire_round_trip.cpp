// The recording's numbers carry exactly what the wire carries: for every raw integer of every
// signal in the recording's range (exhaustively where the range allows, the full edges and a
// stride elsewhere), printing the value, parsing the printed cell back and encoding it again gives
// the same raw integer — through the real encoders (protocol::encode, encode_em_pose,
// encode_tip_force) and the DBC's / serial spec's resolutions, not the code under test's.
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "host_sim/recording/recording_format.hpp"
#include "host_sim/recording/recording_reader.hpp"
#include "host_sim/recording/wire_values.hpp"
#include "protocol/can/can_signal.hpp"
#include "protocol/can/scopekin_messages.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace {

using scopekin::recording::EmPoseCells;
using scopekin::recording::ForceTorqueCells;
using scopekin::recording::InsertionRollCells;
using scopekin::recording::RecordingRow;
using scopekin::recording::TipForceCells;
namespace wire = scopekin::recording::wire;
namespace protocol = scopekin::protocol;

// Column positions in the writer's order (RECORDING.md).
constexpr std::size_t kForce = 1, kTorque = 2, kInsertion = 3, kRoll = 4, kEmTip = 5,
                      kTipForce = 33;

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> cells;
    std::size_t start = 0;
    for (std::size_t comma; (comma = line.find(',', start)) != std::string::npos; start = comma + 1)
        cells.push_back(line.substr(start, comma - start));
    cells.push_back(line.substr(start));
    return cells;
}

double parse(const std::string& text) {
    double value = 0;
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    EXPECT_TRUE(result.ec == std::errc() && result.ptr == text.data() + text.size()) << text;
    return value;
}

std::size_t decimals(const std::string& text) {
    const std::size_t dot = text.find('.');
    return dot == std::string::npos ? 0 : text.size() - dot - 1;
}

/// Raw value of a CAN signal in an encoded frame (the protocol's own bit reader).
std::int64_t frame_raw(const scopekin::hal::CanFrame& frame, const protocol::CanSignal& signal) {
    return protocol::read_raw(frame.data, signal);
}

/// The printed cell of `column` for a row holding only what `fill` puts in.
template <typename Fill>
std::string cell_of(std::size_t column, Fill fill) {
    RecordingRow row;
    row.time_us = 1;
    fill(row);
    return split(scopekin::recording::format_recording_row(row))[column];
}

TEST(RecordingWire, HandleForceEveryRawValueRoundTripsThroughTheCanEncoder) {
    const auto& signal = wire::handle_force_signal();
    for (std::int64_t raw = -32768; raw <= 32767; ++raw) {
        const double value = static_cast<double>(raw) * 0.005;  // the DBC's factor
        const std::string text = cell_of(kForce, [&](RecordingRow& r) {
            r.handle = ForceTorqueCells{value, 0.0};
        });
        ASSERT_EQ(decimals(text), 3u) << text;
        const double parsed = parse(text);
        ASSERT_NEAR(parsed * 200.0, static_cast<double>(raw), 1e-6) << text;
        const auto frame = protocol::encode(wire::to_handle_force_torque({parsed, 0.0}, 0));
        ASSERT_EQ(frame_raw(frame, signal), raw) << text;
    }
}

TEST(RecordingWire, HandleTorqueEveryRawValueRoundTripsThroughTheCanEncoder) {
    const auto& signal = wire::handle_torque_signal();
    for (std::int64_t raw = -32768; raw <= 32767; ++raw) {
        const double value = static_cast<double>(raw) * 0.1;
        const std::string text = cell_of(kTorque, [&](RecordingRow& r) {
            r.handle = ForceTorqueCells{0.0, value};
        });
        ASSERT_EQ(decimals(text), 1u) << text;
        const double parsed = parse(text);
        ASSERT_NEAR(parsed * 10.0, static_cast<double>(raw), 1e-6) << text;
        const auto frame = protocol::encode(wire::to_handle_force_torque({0.0, parsed}, 0));
        ASSERT_EQ(frame_raw(frame, signal), raw) << text;
    }
}

TEST(RecordingWire, InsertionEveryRawValueOfTheRecordingRangeRoundTrips) {
    const auto& signal = wire::insertion_signal();
    for (std::int64_t raw = -5000; raw <= 250000; ++raw) {  // [-50, 2500] mm at 0.01 mm
        const double value = static_cast<double>(raw) * 0.01;
        const std::string text = cell_of(kInsertion, [&](RecordingRow& r) {
            r.insertion_roll = InsertionRollCells{value, 0.0};
        });
        ASSERT_EQ(decimals(text), 2u) << text;
        const double parsed = parse(text);
        ASSERT_NEAR(parsed * 100.0, static_cast<double>(raw), 1e-6) << text;
        const auto frame = protocol::encode(wire::to_insertion_roll({parsed, 0.0}, 0));
        ASSERT_EQ(frame_raw(frame, signal), raw) << text;
    }
}

TEST(RecordingWire, RollRoundTripsOverTheCentreTheEdgesAndAStrideOfTheWholeRange) {
    const auto& signal = wire::roll_signal();
    std::vector<std::int64_t> raws;
    const std::int64_t lo = -(std::int64_t{1} << 23),
                       hi = (std::int64_t{1} << 23) - 1;  // ±838.86 rad
    for (std::int64_t r = -(1 << 20); r <= (1 << 20); ++r)
        raws.push_back(r);  // ±104.9 rad, every step
    for (std::int64_t r = lo; r < lo + 65536; ++r)
        raws.push_back(r);
    for (std::int64_t r = hi - 65535; r <= hi; ++r)
        raws.push_back(r);
    for (std::int64_t r = lo; r <= hi; r += 997)
        raws.push_back(r);
    for (const std::int64_t raw : raws) {
        const double value = static_cast<double>(raw) * 0.0001;
        const std::string text = cell_of(kRoll, [&](RecordingRow& r) {
            r.insertion_roll = InsertionRollCells{0.0, value};
        });
        ASSERT_EQ(decimals(text), 4u) << text;
        const double parsed = parse(text);
        ASSERT_NEAR(parsed * 10000.0, static_cast<double>(raw), 1e-6) << text;
        const auto frame = protocol::encode(wire::to_insertion_roll({0.0, parsed}, 0));
        ASSERT_EQ(frame_raw(frame, signal), raw) << text;
    }
}

TEST(RecordingWire, EmPositionEveryMicrometreOfTheRangeRoundTrips) {
    for (std::int64_t um = -1'000'000; um <= 1'000'000; ++um) {
        const double value = static_cast<double>(um) / 1000.0;
        const std::string text = cell_of(kEmTip, [&](RecordingRow& r) {
            r.em[0] = EmPoseCells{{value, 0.0, 0.0}, {1, 0, 0, 0}};
        });
        ASSERT_EQ(decimals(text), 3u) << text;
        const double parsed = parse(text);
        ASSERT_EQ(wire::to_em_pose({{parsed, 0.0, 0.0}, {1, 0, 0, 0}}, 0, 0).position_um[0], um)
            << text;
    }
    // Through the serial encoder for the edges, every axis and sensor.
    for (const std::int64_t um :
         {-1'000'000LL, -999'999LL, -1LL, 0LL, 1LL, 12'345LL, 999'999LL, 1'000'000LL}) {
        for (std::size_t slot = 0; slot < 4; ++slot) {
            for (std::size_t axis = 0; axis < 3; ++axis) {
                RecordingRow row;
                EmPoseCells pose;
                pose.position_mm[axis] = static_cast<double>(um) / 1000.0;
                row.em[slot] = pose;
                const auto cells = split(scopekin::recording::format_recording_row(row));
                EmPoseCells parsed;
                for (std::size_t i = 0; i < 3; ++i)
                    parsed.position_mm[i] = parse(cells[kEmTip + slot * 7 + i]);
                for (std::size_t i = 0; i < 4; ++i)
                    parsed.quaternion_wxyz[i] = parse(cells[kEmTip + slot * 7 + 3 + i]);
                std::array<std::uint8_t, protocol::kEmTrackerMaxFrameSize> bytes{};
                ASSERT_EQ(protocol::encode_em_pose(
                              wire::to_em_pose(parsed, static_cast<std::uint8_t>(slot), 7), bytes),
                          32u);
                // x at payload offset 6 (+ 4 header bytes), little-endian int32 (em_tracker_serial.md §3).
                const std::size_t at = 4 + 6 + 4 * axis;
                const auto bits = static_cast<std::uint32_t>(bytes[at]) |
                                  (static_cast<std::uint32_t>(bytes[at + 1]) << 8U) |
                                  (static_cast<std::uint32_t>(bytes[at + 2]) << 16U) |
                                  (static_cast<std::uint32_t>(bytes[at + 3]) << 24U);
                ASSERT_EQ(static_cast<std::int32_t>(bits), um);
                ASSERT_EQ(bytes[4 + 4], slot);  // sensor id
            }
        }
    }
}

TEST(RecordingWire, QuaternionEveryQ14ValueRoundTrips) {
    for (std::size_t component = 1; component < 4; ++component) {
        for (std::int64_t raw = -16384; raw <= 16384; ++raw) {
            const double c = static_cast<double>(raw) / 16384.0;
            RecordingRow row;
            EmPoseCells pose;
            pose.quaternion_wxyz = {std::sqrt(std::max(0.0, 1.0 - c * c)), 0.0, 0.0, 0.0};
            pose.quaternion_wxyz[component] = c;
            row.em[1] = pose;
            const auto cells = split(scopekin::recording::format_recording_row(row));
            const std::string& text = cells[kEmTip + 7 + 3 + component];
            ASSERT_EQ(decimals(text), 6u) << text;
            const double parsed = parse(text);
            ASSERT_NEAR(parsed, c, 5.0000001e-7)
                << text;  // printed to 6 decimals of the exact value
            ASSERT_EQ(wire::quaternion_q14(parsed), raw) << text;
            // And w, which is off the grid before printing: the printed w encodes as round(w * 16384).
            const double w_parsed = parse(cells[kEmTip + 7 + 3]);
            ASSERT_EQ(wire::quaternion_q14(w_parsed),
                      std::llround(pose.quaternion_wxyz[0] * 16384.0))
                << raw;
        }
    }
}

TEST(RecordingWire, TipForceEveryMillinewtonOfTheRangeRoundTripsThroughTheSerialEncoder) {
    for (std::int64_t mN = -25000; mN <= 25000; ++mN) {
        const double value = static_cast<double>(mN) / 1000.0;
        for (std::size_t axis : {0u, 2u}) {
            RecordingRow row;
            TipForceCells force;
            force.force_N[axis] = value;
            row.tip_force = force;
            const std::string text =
                split(scopekin::recording::format_recording_row(row))[kTipForce + axis];
            ASSERT_EQ(decimals(text), 3u) << text;
            TipForceCells parsed;
            parsed.force_N[axis] = parse(text);
            std::array<std::uint8_t, protocol::kEmTrackerMaxFrameSize> bytes{};
            ASSERT_EQ(protocol::encode_tip_force(wire::to_tip_force(parsed, 0), bytes), 17u);
            const std::size_t at = 4 + 5 + 2 * axis;  // payload offset 5: force x, int16 LE
            const auto bits = static_cast<std::uint16_t>(bytes[at] | (bytes[at + 1] << 8U));
            ASSERT_EQ(static_cast<std::int16_t>(bits), mN) << text;
        }
    }
}

TEST(RecordingWire, OffGridValuesPrintWhatTheWireWouldCarry) {
    // Values between the steps (including ties and the neighbours of ties): the printed cell
    // encodes to the raw integer of the original value.
    std::uint64_t state = 12345;
    auto uniform = [&state] {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return static_cast<double>(state >> 11U) / 9007199254740992.0;
    };
    for (int i = 0; i < 100000; ++i) {
        const double f = -163.0 + 326.0 * uniform();
        const double t = -3270.0 + 6540.0 * uniform();
        const double ins = -49.0 + 2548.0 * uniform();
        const double roll = -830.0 + 1660.0 * uniform();
        const double tie_f =
            (std::floor(f * 200.0) + 0.5) / 200.0;  // a tie (or its nearest double)
        for (const double force :
             {f, tie_f, std::nextafter(tie_f, 1e9), std::nextafter(tie_f, -1e9)}) {
            RecordingRow row;
            row.handle = ForceTorqueCells{force, t};
            row.insertion_roll = InsertionRollCells{ins, roll};
            const auto cells = split(scopekin::recording::format_recording_row(row));
            ASSERT_EQ(wire::handle_force_raw(parse(cells[kForce])), wire::handle_force_raw(force))
                << force;
            ASSERT_EQ(wire::handle_torque_raw(parse(cells[kTorque])), wire::handle_torque_raw(t))
                << t;
            ASSERT_EQ(wire::insertion_raw(parse(cells[kInsertion])), wire::insertion_raw(ins))
                << ins;
            ASSERT_EQ(wire::roll_raw(parse(cells[kRoll])), wire::roll_raw(roll)) << roll;
            // The raw integer of the value is round(value / resolution): independent check.
            ASSERT_LE(std::abs(parse(cells[kForce]) - force), 0.0025 + 1e-12);
        }
    }
}

TEST(RecordingWire, NoNegativeZeroAndExactDecimals) {
    RecordingRow row;
    row.handle = ForceTorqueCells{-0.0001, -0.04};  // both round to raw 0
    row.insertion_roll = InsertionRollCells{-0.004, -0.00004};
    row.tip_force = TipForceCells{{-0.0004, 0.0, -0.0}};
    const auto cells = split(scopekin::recording::format_recording_row(row));
    EXPECT_EQ(cells[kForce], "0.000");
    EXPECT_EQ(cells[kTorque], "0.0");
    EXPECT_EQ(cells[kInsertion], "0.00");
    EXPECT_EQ(cells[kRoll], "0.0000");
    EXPECT_EQ(cells[kTipForce], "0.000");
    row.handle = ForceTorqueCells{-163.84, 3276.7};
    row.insertion_roll = InsertionRollCells{2500.0, -838.8608};
    const auto edge = split(scopekin::recording::format_recording_row(row));
    EXPECT_EQ(edge[kForce], "-163.840");
    EXPECT_EQ(edge[kTorque], "3276.7");
    EXPECT_EQ(edge[kInsertion], "2500.00");
    EXPECT_EQ(edge[kRoll], "-838.8608");
}

TEST(RecordingWire, TimePrintsMicrosecondsExactly) {
    for (const std::int64_t us :
         {0LL, 1LL, 999'999LL, 1'000'000LL, 1'234'567LL, 4'294'967'295LL, 4'294'967'296LL,
          999'999'999'999'999LL, 1'000'000'000'000'000LL}) {
        RecordingRow row;
        row.time_us = us;
        const std::string text = split(scopekin::recording::format_recording_row(row))[0];
        ASSERT_EQ(decimals(text), 6u) << text;
        // Independent: seconds and micro-seconds from the text's digits.
        const std::size_t dot = text.find('.');
        const std::int64_t seconds = std::stoll(text.substr(0, dot));
        const std::int64_t micro = std::stoll(text.substr(dot + 1));
        EXPECT_EQ(seconds * 1'000'000 + micro, us) << text;
    }
    EXPECT_EQ(scopekin::recording::format_time_s(1'234'000), "1.234000");
}

TEST(RecordingWire, AFileOfEdgeRowsReadsBackToTheSameIntegersAndTheSameText) {
    std::vector<RecordingRow> rows;
    std::int64_t t = 0;
    auto add = [&](RecordingRow row) {
        row.time_us = t;
        t += 1000;
        rows.push_back(row);
    };
    for (const double f : {-163.84, -163.835, -0.005, 0.0, 0.005, 43.0, 163.83, 163.835}) {
        RecordingRow r;
        r.handle = ForceTorqueCells{f, -f * 19.0};
        add(r);
    }
    for (const double ins : {-50.0, -49.99, 0.0, 0.01, 1234.56, 2499.99, 2500.0}) {
        RecordingRow r;
        r.insertion_roll = InsertionRollCells{ins, ins / 3.0};
        r.region = "sigmoid";
        add(r);
    }
    for (const double p : {-1000.0, -999.999, -0.001, 0.0, 0.001, 999.999, 1000.0}) {
        RecordingRow r;
        const double a = 0.3;
        r.em[0] = EmPoseCells{{p, -p, p / 7.0}, {std::cos(a), std::sin(a), 0.0, 0.0}};
        r.em[3] = EmPoseCells{{p / 3.0, 0.5, -p}, {0.5, 0.5, 0.5, 0.5}};
        r.tip_force = TipForceCells{{p / 40.0, -p / 40.0, 25.0}};
        add(r);
    }
    std::ostringstream first;
    {
        scopekin::recording::RecordingWriter writer(first);
        for (const auto& row : rows)
            writer.write(row);
    }
    std::istringstream in(first.str());
    const auto recording = scopekin::recording::RecordingReader().read(in);
    ASSERT_EQ(recording.rows.size(), rows.size());
    std::ostringstream second;
    {
        scopekin::recording::RecordingWriter writer(second);
        for (std::size_t i = 0; i < rows.size(); ++i) {
            EXPECT_EQ(wire::quantize_to_wire(recording.rows[i]), wire::quantize_to_wire(rows[i]))
                << "row " << i;
            writer.write(recording.rows[i]);
        }
    }
    EXPECT_EQ(second.str(), first.str());
}

}  // namespace
