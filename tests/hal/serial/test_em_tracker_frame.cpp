// EM-tracker serial protocol: CRC, the spec's worked examples byte for byte, encoder/decoder round
// trips, and the framer against garbage, splits, corruption, fake headers, overflow and a
// randomised hostile stream.  Runs as GoogleTest on x86-64 / aarch64 and with portable_check's
// runner on Cortex-M4 (firmware/protocol/em_tracker/em_tracker_serial.md is the reference).
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include "em_tracker_stream.hpp"
#include "em_tracker_test_bytes.hpp"
#include "portable_check.hpp"
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace {

using scopekin::protocol::decode_em_pose;
using scopekin::protocol::decode_tip_force;
using scopekin::protocol::em_tracker_crc16;
using scopekin::protocol::EmPoseMessage;
using scopekin::protocol::EmTrackerFrame;
using scopekin::protocol::EmTrackerFramer;
using scopekin::protocol::EmTrackerFramerCounters;
using scopekin::protocol::EmTrackerMessageType;
using scopekin::protocol::encode_em_pose;
using scopekin::protocol::encode_em_tracker_frame;
using scopekin::protocol::encode_tip_force;
using scopekin::protocol::kEmTrackerFramerCapacity;
using scopekin::protocol::kEmTrackerMaxFrameSize;
using scopekin::protocol::TipForceMessage;
using scopekin::test::kSpecPose;
using scopekin::test::kSpecTipForce;
using scopekin::test::spec_pose;
using Bytes = std::span<const std::uint8_t>;

// CRC-16/CCITT-FALSE check value.
constexpr std::array<std::uint8_t, 9> kCheckInput{'1', '2', '3', '4', '5', '6', '7', '8', '9'};
static_assert(em_tracker_crc16(Bytes{kCheckInput}) == 0x29B1U);

// em_tracker_serial.md §5, copied from the document (the messages: em_tracker_test_bytes.hpp).
constexpr std::array<std::uint8_t, 32> kSpecPoseFrame{
    0xA5, 0x5A, 0x01, 0x1A, 0x40, 0x42, 0x0F, 0x00, 0x00, 0x00, 0x39, 0x30, 0x00, 0x00, 0x7B, 0xE5,
    0xFF, 0xFF, 0x90, 0xD0, 0x03, 0x00, 0x41, 0x2D, 0x00, 0x00, 0x00, 0x00, 0x41, 0x2D, 0xCB, 0x4B};
constexpr std::array<std::uint8_t, 17> kSpecTipForceFrame{0xA5, 0x5A, 0x02, 0x0B, 0x3A, 0x43,
                                                          0x0F, 0x00, 0x00, 0x6A, 0xFF, 0x28,
                                                          0x00, 0xC4, 0x09, 0x87, 0x60};
static_assert(em_tracker_crc16(Bytes{kSpecPoseFrame}.subspan(2, 28)) == 0x4BCBU);
static_assert(em_tracker_crc16(Bytes{kSpecTipForceFrame}.subspan(2, 13)) == 0x6087U);

/// What came out of a framer, kept for comparison (static storage: the bare-metal stack is small).
struct FrameLog {
    static constexpr std::size_t kCapacity = 64;
    std::array<EmTrackerFrame, kCapacity> frames{};
    std::size_t count{0};
    std::size_t frame_bytes{0};  ///< sum of the popped frames' sizes
};

void pop_all(EmTrackerFramer& framer, FrameLog& log) {
    EmTrackerFrame frame;
    for (std::size_t i = 0; i < kEmTrackerFramerCapacity; ++i) {
        if (!framer.pop(frame)) {
            return;
        }
        if (log.count < FrameLog::kCapacity) {
            log.frames[log.count] = frame;
        }
        ++log.count;
        log.frame_bytes += frame.payload_length + scopekin::protocol::kEmTrackerOverhead;
    }
}

/// Pushes `bytes` in chunks of `chunk` bytes, popping every frame after each push.  Returns the
/// number of bytes the framer took.
std::size_t feed(EmTrackerFramer& framer, Bytes bytes, std::size_t chunk, FrameLog& log) {
    std::size_t taken = 0;
    for (std::size_t offset = 0; offset < bytes.size(); offset += chunk) {
        const std::size_t size = bytes.size() - offset < chunk ? bytes.size() - offset : chunk;
        taken += framer.push(bytes.subspan(offset, size));
        pop_all(framer, log);
    }
    return taken;
}

/// The framer's byte accounting: every accepted byte is in a frame, discarded or still buffered.
bool bytes_accounted(const EmTrackerFramer& framer, std::size_t accepted, const FrameLog& log) {
    return accepted == log.frame_bytes + framer.counters().bytes_discarded + framer.buffered();
}

/// `bytes` starts with `prefix`, byte for byte.
bool begins_with(Bytes bytes, Bytes prefix) {
    bool same = bytes.size() >= prefix.size();
    for (std::size_t i = 0; same && i < prefix.size(); ++i) {
        same = bytes[i] == prefix[i];
    }
    return same;
}

bool same_pose(const EmTrackerFrame& frame, const EmPoseMessage& expected) {
    EmPoseMessage decoded;
    return decode_em_pose(frame, decoded) && decoded == expected;
}

bool same_tip_force(const EmTrackerFrame& frame, const TipForceMessage& expected) {
    TipForceMessage decoded;
    return decode_tip_force(frame, decoded) && decoded == expected;
}

bool counters_equal(const EmTrackerFramerCounters& a, const EmTrackerFramerCounters& b) {
    return a.frames_ok == b.frames_ok && a.bad_checksum == b.bad_checksum &&
           a.bad_length == b.bad_length && a.unknown_type == b.unknown_type &&
           a.bytes_discarded == b.bytes_discarded && a.buffer_overflows == b.buffer_overflows;
}

/// A little stream builder over static storage.
using Stream = scopekin::test::EmTrackerTestBytes<1024>;

// Static storage of the tests below (the bare-metal stack is 32 KiB).
FrameLog g_log;
Stream g_stream;
EmTrackerFramer g_framer;

void reset() {
    g_log = FrameLog{};
    g_stream = Stream{};
    g_framer = EmTrackerFramer{};
}

}  // namespace

SCOPEKIN_TEST(EmTrackerCrc, CheckValueAndSpecExamples) {
    SCOPEKIN_EXPECT_EQ(em_tracker_crc16(Bytes{kCheckInput}), 0x29B1U);
    SCOPEKIN_EXPECT_EQ(em_tracker_crc16(Bytes{}), 0xFFFFU);  // init, nothing fed
    SCOPEKIN_EXPECT_EQ(em_tracker_crc16(Bytes{kSpecPoseFrame}.subspan(2, 28)), 0x4BCBU);
    SCOPEKIN_EXPECT_EQ(em_tracker_crc16(Bytes{kSpecTipForceFrame}.subspan(2, 13)), 0x6087U);
}

SCOPEKIN_TEST(EmTrackerFrame, SpecPoseExampleIsByteExact) {
    std::array<std::uint8_t, 40> out{};
    const std::size_t size = encode_em_pose(kSpecPose, out);
    SCOPEKIN_EXPECT_EQ(size, kSpecPoseFrame.size());
    SCOPEKIN_EXPECT_TRUE(begins_with(out, kSpecPoseFrame));

    reset();
    feed(g_framer, Bytes{kSpecPoseFrame}, kSpecPoseFrame.size(), g_log);
    SCOPEKIN_EXPECT_EQ(g_log.count, 1U);
    SCOPEKIN_EXPECT_TRUE(g_log.frames[0].type == EmTrackerMessageType::pose);
    SCOPEKIN_EXPECT_TRUE(same_pose(g_log.frames[0], kSpecPose));
}

SCOPEKIN_TEST(EmTrackerFrame, SpecTipForceExampleIsByteExact) {
    std::array<std::uint8_t, 40> out{};
    const std::size_t size = encode_tip_force(kSpecTipForce, out);
    SCOPEKIN_EXPECT_EQ(size, kSpecTipForceFrame.size());
    SCOPEKIN_EXPECT_TRUE(begins_with(out, kSpecTipForceFrame));

    reset();
    feed(g_framer, Bytes{kSpecTipForceFrame}, 1, g_log);
    SCOPEKIN_EXPECT_EQ(g_log.count, 1U);
    SCOPEKIN_EXPECT_TRUE(same_tip_force(g_log.frames[0], kSpecTipForce));
}

SCOPEKIN_TEST(EmTrackerFrame, RoundTripOfEveryMessageTypeAtTheFieldLimits) {
    constexpr std::int32_t i32_min = std::numeric_limits<std::int32_t>::min();
    constexpr std::int32_t i32_max = std::numeric_limits<std::int32_t>::max();
    constexpr std::int16_t i16_min = std::numeric_limits<std::int16_t>::min();
    constexpr std::int16_t i16_max = std::numeric_limits<std::int16_t>::max();
    const EmPoseMessage poses[] = {
        kSpecPose,
        {0xFFFFFFFFU, 255U, 255U, {i32_min, i32_max, -1}, {i16_min, i16_max, -1, 0}},
        {0U, 3U, 0U, {0, 0, 0}, {16384, 0, 0, 0}},
    };
    const TipForceMessage forces[] = {
        kSpecTipForce,
        {0xFFFFFFFFU, 255U, {i16_min, i16_max, -1}},
        {0U, 0U, {0, 0, 0}},
    };
    reset();
    for (const EmPoseMessage& pose : poses) {
        g_stream.add_pose(pose);
    }
    for (const TipForceMessage& force : forces) {
        g_stream.add_tip_force(force);
    }
    const std::size_t accepted = feed(g_framer, g_stream.view(), 7, g_log);
    SCOPEKIN_EXPECT_EQ(g_log.count, 6U);
    for (std::size_t i = 0; i < 3U; ++i) {
        SCOPEKIN_EXPECT_TRUE(same_pose(g_log.frames[i], poses[i]));
        SCOPEKIN_EXPECT_TRUE(same_tip_force(g_log.frames[3U + i], forces[i]));
        // The decoders refuse the other type.
        EmPoseMessage pose;
        TipForceMessage force;
        SCOPEKIN_EXPECT_TRUE(!decode_em_pose(g_log.frames[3U + i], pose));
        SCOPEKIN_EXPECT_TRUE(!decode_tip_force(g_log.frames[i], force));
    }
    SCOPEKIN_EXPECT_EQ(g_framer.counters().frames_ok, 6U);
    SCOPEKIN_EXPECT_EQ(g_framer.counters().bytes_discarded, 0U);
    SCOPEKIN_EXPECT_TRUE(bytes_accounted(g_framer, accepted, g_log));
}

SCOPEKIN_TEST(EmTrackerFrame, EncoderRefusesSmallBuffersAndLongPayloads) {
    std::array<std::uint8_t, 31> small{};
    SCOPEKIN_EXPECT_EQ(encode_em_pose(kSpecPose, small), 0U);
    SCOPEKIN_EXPECT_EQ(encode_tip_force(kSpecTipForce, std::span<std::uint8_t>{small.data(), 16}),
                       0U);
    static std::array<std::uint8_t, 300> big{};
    static std::array<std::uint8_t, 310> out{};
    SCOPEKIN_EXPECT_EQ(encode_em_tracker_frame(0x01U, Bytes{big.data(), 256}, out), 0U);
    SCOPEKIN_EXPECT_EQ(encode_em_tracker_frame(0x01U, Bytes{big.data(), 255}, out), 261U);
    SCOPEKIN_EXPECT_EQ(encode_em_tracker_frame(0x7FU, Bytes{}, out), 6U);
}

SCOPEKIN_TEST(EmTrackerFramer, ResynchronisesAfterGarbage) {
    reset();
    const std::array<std::uint8_t, 10> garbage{0x00, 0xA5, 0xA5, 0x11, 0x5A,
                                               0xA5, 0x5A, 0xFF, 0xA5, 0x13};
    g_stream.add(garbage);
    g_stream.add_pose(spec_pose(0U, 1));
    g_stream.add(garbage);
    g_stream.add_tip_force(kSpecTipForce);
    g_stream.add_pose(spec_pose(0U, 2));
    const std::size_t accepted = feed(g_framer, g_stream.view(), g_stream.size, g_log);
    SCOPEKIN_EXPECT_EQ(g_log.count, 3U);
    SCOPEKIN_EXPECT_TRUE(same_pose(g_log.frames[0], spec_pose(0U, 1)));
    SCOPEKIN_EXPECT_TRUE(same_tip_force(g_log.frames[1], kSpecTipForce));
    SCOPEKIN_EXPECT_TRUE(same_pose(g_log.frames[2], spec_pose(0U, 2)));
    SCOPEKIN_EXPECT_EQ(g_framer.counters().bytes_discarded, 20U);  // exactly the garbage
    SCOPEKIN_EXPECT_EQ(g_framer.counters().unknown_type, 2U);      // A5 5A FF, twice
    SCOPEKIN_EXPECT_EQ(g_framer.buffered(), 0U);
    SCOPEKIN_EXPECT_TRUE(bytes_accounted(g_framer, accepted, g_log));
}

SCOPEKIN_TEST(EmTrackerFramer, FrameSplitByteByByteComesOutOnItsLastByte) {
    reset();
    g_stream.add_pose(kSpecPose);
    g_stream.add_tip_force(kSpecTipForce);
    EmTrackerFrame frame;
    std::size_t frames = 0;
    for (std::size_t i = 0; i < g_stream.size; ++i) {
        SCOPEKIN_EXPECT_TRUE(g_framer.push(g_stream.bytes[i]));
        const bool complete = g_framer.pop(frame);
        const bool last_byte_of_a_frame = i == 31U || i == 48U;
        SCOPEKIN_EXPECT_EQ(complete, last_byte_of_a_frame);
        if (complete) {
            ++frames;
            SCOPEKIN_EXPECT_TRUE(frames == 1U ? same_pose(frame, kSpecPose)
                                              : same_tip_force(frame, kSpecTipForce));
        }
    }
    SCOPEKIN_EXPECT_EQ(frames, 2U);
    SCOPEKIN_EXPECT_EQ(g_framer.counters().bytes_discarded, 0U);
}

SCOPEKIN_TEST(EmTrackerFramer, CorruptedChecksumImmediatelyFollowedByAValidFrame) {
    reset();
    std::array<std::uint8_t, 32> bad = kSpecPoseFrame;
    bad[31] = static_cast<std::uint8_t>(bad[31] ^ 0x01U);  // CRC high byte
    g_stream.add(bad);
    g_stream.add_pose(spec_pose(0U, 7));
    std::array<std::uint8_t, 17> bad_force = kSpecTipForceFrame;
    bad_force[9] = static_cast<std::uint8_t>(bad_force[9] ^ 0x80U);  // payload
    g_stream.add(bad_force);
    g_stream.add_tip_force(kSpecTipForce);
    const std::size_t accepted = feed(g_framer, g_stream.view(), 5, g_log);
    SCOPEKIN_EXPECT_EQ(g_log.count, 2U);
    SCOPEKIN_EXPECT_TRUE(same_pose(g_log.frames[0], spec_pose(0U, 7)));
    SCOPEKIN_EXPECT_TRUE(same_tip_force(g_log.frames[1], kSpecTipForce));
    SCOPEKIN_EXPECT_EQ(g_framer.counters().bad_checksum, 2U);
    SCOPEKIN_EXPECT_EQ(g_framer.counters().bytes_discarded, 32U + 17U);
    SCOPEKIN_EXPECT_TRUE(bytes_accounted(g_framer, accepted, g_log));
}

SCOPEKIN_TEST(EmTrackerFramer, ValidFrameStartingInsideACorruptedFrameIsFound) {
    // A pose frame whose payload carries a complete tip force frame (17 of its 26 bytes) and whose
    // CRC is wrong: the pose is rejected, the force frame inside it must come out.
    reset();
    std::array<std::uint8_t, 26> payload{};
    for (std::size_t i = 0; i < kSpecTipForceFrame.size(); ++i) {
        payload[4U + i] = kSpecTipForceFrame[i];
    }
    std::array<std::uint8_t, 32> carrier{};
    SCOPEKIN_EXPECT_EQ(encode_em_tracker_frame(0x01U, payload, carrier), 32U);
    carrier[30] = static_cast<std::uint8_t>(carrier[30] ^ 0xFFU);  // break the pose's CRC
    g_stream.add(carrier);
    // A truncated pose (the line lost its tail) directly followed by a valid pose.
    g_stream.add(Bytes{kSpecPoseFrame}.first(20));
    g_stream.add_pose(spec_pose(0U, 9));
    const std::size_t accepted = feed(g_framer, g_stream.view(), 3, g_log);
    SCOPEKIN_EXPECT_EQ(g_log.count, 2U);
    SCOPEKIN_EXPECT_TRUE(same_tip_force(g_log.frames[0], kSpecTipForce));
    SCOPEKIN_EXPECT_TRUE(same_pose(g_log.frames[1], spec_pose(0U, 9)));
    SCOPEKIN_EXPECT_EQ(g_framer.counters().bad_checksum, 2U);  // the carrier, the truncated pose
    SCOPEKIN_EXPECT_EQ(g_framer.counters().bytes_discarded, (32U - 17U) + 20U);
    SCOPEKIN_EXPECT_TRUE(bytes_accounted(g_framer, accepted, g_log));
}

SCOPEKIN_TEST(EmTrackerFramer, FakeSyncWithHugeLengthDoesNotSwallowTheFramesAfterIt) {
    reset();
    const std::array<std::uint8_t, 4> fake_pose{0xA5, 0x5A, 0x01, 0xFF};
    const std::array<std::uint8_t, 4> fake_force{0xA5, 0x5A, 0x02, 0xC8};
    g_stream.add(fake_pose);
    g_stream.add_pose(spec_pose(0U, 1));
    g_stream.add(fake_force);
    g_stream.add_tip_force(kSpecTipForce);
    // Fed in one go: the frames come out at once, nothing waits for 255 bytes.
    const std::size_t accepted = feed(g_framer, g_stream.view(), g_stream.size, g_log);
    SCOPEKIN_EXPECT_EQ(g_log.count, 2U);
    SCOPEKIN_EXPECT_TRUE(same_pose(g_log.frames[0], spec_pose(0U, 1)));
    SCOPEKIN_EXPECT_TRUE(same_tip_force(g_log.frames[1], kSpecTipForce));
    SCOPEKIN_EXPECT_EQ(g_framer.counters().bad_length, 2U);
    SCOPEKIN_EXPECT_EQ(g_framer.counters().bytes_discarded, 8U);
    SCOPEKIN_EXPECT_EQ(g_framer.buffered(), 0U);
    SCOPEKIN_EXPECT_TRUE(bytes_accounted(g_framer, accepted, g_log));
}

SCOPEKIN_TEST(EmTrackerFramer, EveryCounter) {
    reset();
    std::array<std::uint8_t, 40> frame{};
    const std::array<std::uint8_t, 26> payload26{};
    const std::array<std::uint8_t, 11> payload11{};
    // 1 valid pose (32 bytes, ok)
    g_stream.add_pose(kSpecPose);
    // 2 unknown type with a correct CRC (6 + 26 bytes): only its first byte is dropped at a time;
    //   its remaining 31 bytes are zeros -> discarded one by one
    g_stream.add(Bytes{frame.data(), encode_em_tracker_frame(0x03U, payload26, frame)});
    // 3 known type, wrong length, correct CRC (a pose with an 11-byte payload: 17 bytes)
    g_stream.add(Bytes{frame.data(), encode_em_tracker_frame(0x01U, payload11, frame)});
    // 4 bad checksum (17 bytes)
    std::array<std::uint8_t, 17> bad = kSpecTipForceFrame;
    bad[16] = static_cast<std::uint8_t>(bad[16] + 1U);
    g_stream.add(bad);
    // 5 valid tip force
    g_stream.add_tip_force(kSpecTipForce);
    const std::size_t accepted = feed(g_framer, g_stream.view(), g_stream.size, g_log);
    EmTrackerFramerCounters expected;
    expected.frames_ok = 2;
    expected.unknown_type = 1;
    expected.bad_length = 1;
    expected.bad_checksum = 1;
    expected.bytes_discarded = 32 + 17 + 17;
    expected.buffer_overflows = 0;
    SCOPEKIN_EXPECT_TRUE(counters_equal(g_framer.counters(), expected));
    SCOPEKIN_EXPECT_EQ(g_log.count, 2U);
    SCOPEKIN_EXPECT_TRUE(bytes_accounted(g_framer, accepted, g_log));

    // Overflow: 300 bytes at once into a 256-byte ring.
    static std::array<std::uint8_t, 300> zeros{};
    const std::size_t taken = g_framer.push(zeros);
    SCOPEKIN_EXPECT_EQ(taken, kEmTrackerFramerCapacity);
    SCOPEKIN_EXPECT_EQ(g_framer.counters().buffer_overflows, 1U);
    SCOPEKIN_EXPECT_TRUE(!g_framer.push(std::uint8_t{0}));
    SCOPEKIN_EXPECT_EQ(g_framer.counters().buffer_overflows, 2U);
    pop_all(g_framer, g_log);  // all zeros: discarded
    SCOPEKIN_EXPECT_EQ(g_framer.buffered(), 0U);
    SCOPEKIN_EXPECT_TRUE(bytes_accounted(g_framer, accepted + taken, g_log));

    // clear(): the buffered partial frame counts as discarded.
    SCOPEKIN_EXPECT_EQ(g_framer.push(Bytes{kSpecPoseFrame}.first(10)), 10U);
    const std::uint32_t discarded_before = g_framer.counters().bytes_discarded;
    g_framer.clear();
    SCOPEKIN_EXPECT_EQ(g_framer.buffered(), 0U);
    SCOPEKIN_EXPECT_EQ(g_framer.counters().bytes_discarded, discarded_before + 10U);
}

SCOPEKIN_TEST(EmTrackerFramer, PartialCandidateLeavesLessThanOneFrameBuffered) {
    reset();
    // A frame's first 31 bytes: the framer must wait (it could still complete) ...
    SCOPEKIN_EXPECT_EQ(g_framer.push(Bytes{kSpecPoseFrame}.first(31)), 31U);
    pop_all(g_framer, g_log);
    SCOPEKIN_EXPECT_EQ(g_log.count, 0U);
    SCOPEKIN_EXPECT_EQ(g_framer.buffered(), 31U);
    SCOPEKIN_EXPECT_TRUE(g_framer.buffered() < kEmTrackerMaxFrameSize);
    // ... and the last byte completes it.
    SCOPEKIN_EXPECT_TRUE(g_framer.push(kSpecPoseFrame[31]));
    pop_all(g_framer, g_log);
    SCOPEKIN_EXPECT_EQ(g_log.count, 1U);
}

// --- Randomised hostile stream ----------------------------------------------------------------------

namespace {

constexpr std::size_t kStressEvents = 6000;
std::array<std::uint8_t, kStressEvents * 32> g_stress_stream{};
std::array<scopekin::test::ExpectedEmMessage, kStressEvents> g_stress_expected{};

}  // namespace

SCOPEKIN_TEST(EmTrackerFramer, RandomisedStreamYieldsExactlyTheValidFrames) {
    using scopekin::test::EmTrackerStreamGenerator;
    const std::uint32_t seeds[] = {1U, 0xC0FFEEU, 20240611U};
    for (const std::uint32_t seed : seeds) {
        EmTrackerStreamGenerator generator(seed);
        std::size_t expected_count = 0;
        const std::size_t size = scopekin::test::generate_em_tracker_stream(
            generator, g_stress_stream, g_stress_expected, kStressEvents, expected_count);
        SCOPEKIN_EXPECT_TRUE(expected_count > kStressEvents / 2U);

        // Random chunk sizes 1..64, every frame popped after each push, compared as it comes.
        EmTrackerFramer framer;
        scopekin::test::TestPrng chunks(seed ^ 0x5A5A5A5AU);
        std::size_t offset = 0;
        std::size_t matched = 0;
        std::size_t popped = 0;
        std::size_t frame_bytes = 0;
        bool in_order = true;
        EmTrackerFrame frame;
        while (offset < size) {
            std::size_t chunk = 1U + chunks.below(64U);
            chunk = chunk < size - offset ? chunk : size - offset;
            offset += framer.push(Bytes{g_stress_stream.data() + offset, chunk});
            while (framer.pop(frame)) {
                frame_bytes += frame.payload_length + scopekin::protocol::kEmTrackerOverhead;
                if (popped < expected_count) {
                    const auto& expected = g_stress_expected[popped];
                    const bool same = frame.type == expected.type &&
                                      (expected.type == EmTrackerMessageType::pose
                                           ? same_pose(frame, expected.pose)
                                           : same_tip_force(frame, expected.tip_force));
                    if (same) {
                        ++matched;
                    } else {
                        in_order = false;
                    }
                }
                ++popped;
            }
            if (framer.buffered() >= kEmTrackerMaxFrameSize) {
                in_order = false;  // pop() must leave less than one frame behind
            }
        }
        SCOPEKIN_EXPECT_EQ(popped, expected_count);
        SCOPEKIN_EXPECT_EQ(matched, expected_count);
        SCOPEKIN_EXPECT_TRUE(in_order);
        SCOPEKIN_EXPECT_EQ(framer.counters().frames_ok, expected_count);
        SCOPEKIN_EXPECT_EQ(framer.counters().buffer_overflows, 0U);
        SCOPEKIN_EXPECT_TRUE(framer.counters().bad_checksum > 0U);
        SCOPEKIN_EXPECT_TRUE(framer.counters().bad_length > 0U);
        SCOPEKIN_EXPECT_TRUE(framer.counters().unknown_type > 0U);
        SCOPEKIN_EXPECT_EQ(size,
                           frame_bytes + framer.counters().bytes_discarded + framer.buffered());
    }
}
