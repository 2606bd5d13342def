// em_tracker_stream.hpp — a simulated EM tracker's byte stream, deterministic and hostile.
//
// Test support shared by the framer/driver tests (every preset, bare metal included: no heap, no
// floating point, no std::random_device) and the pseudo-terminal test: a seeded generator emits
// events — valid pose and tip force frames, noise bursts rich in sync bytes, corrupted frames
// (one byte changed anywhere after the sync), truncated frames, fake headers with huge lengths —
// and reports, for every valid frame, the message it carries, in order.  Whatever the framer and
// the driver make of the stream must be exactly that list.
//
// The valid messages are valid for the driver too: per-sensor device times strictly increase
// (starting 1 s before the 32-bit device clock wraps, so the wrap is always crossed), positions
// within ±900 mm, unit quaternions from a table (with sign flips), forces within ±20 N, status 0.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace scopekin::test {

/// xorshift32 (Marsaglia): deterministic on every target.
class TestPrng {
public:
    explicit constexpr TestPrng(std::uint32_t seed) noexcept
        : state_(seed == 0U ? 0x9E3779B9U : seed) {}
    constexpr std::uint32_t next() noexcept {
        state_ ^= state_ << 13U;
        state_ ^= state_ >> 17U;
        state_ ^= state_ << 5U;
        return state_;
    }
    /// Uniform-ish in [0, bound) (bound > 0; the modulo bias is irrelevant here).
    constexpr std::uint32_t below(std::uint32_t bound) noexcept { return next() % bound; }
    /// Uniform-ish in [-magnitude, magnitude].
    constexpr std::int32_t symmetric(std::int32_t magnitude) noexcept {
        const auto span = static_cast<std::uint32_t>(magnitude) * 2U + 1U;
        return static_cast<std::int32_t>(below(span)) - magnitude;
    }
    constexpr std::uint8_t byte() noexcept { return static_cast<std::uint8_t>(next() >> 24U); }

private:
    std::uint32_t state_;
};

/// The message a valid frame of the stream carries.
struct ExpectedEmMessage {
    protocol::EmTrackerMessageType type{protocol::EmTrackerMessageType::pose};
    protocol::EmPoseMessage pose{};
    protocol::TipForceMessage tip_force{};
};

enum class StreamEvent : std::uint8_t {
    valid_pose,
    valid_tip_force,
    noise,
    corrupted_frame,
    truncated_frame,
    fake_header,
};

/// Largest event, bytes (a corrupted or valid pose frame: 32; noise: at most 24).
inline constexpr std::size_t kMaxStreamEventSize = protocol::kEmTrackerMaxFrameSize;

class EmTrackerStreamGenerator {
public:
    /// `hostile` = false: valid frames only.
    explicit constexpr EmTrackerStreamGenerator(std::uint32_t seed, bool hostile = true) noexcept
        : prng_(seed), hostile_(hostile) {}

    /// Writes the next event to the front of `out` (at least kMaxStreamEventSize bytes); returns
    /// its size (0 if `out` is too small).  For a valid frame sets `is_valid` and `expected`.
    std::size_t next(std::span<std::uint8_t> out, ExpectedEmMessage& expected,
                     bool& is_valid) noexcept {
        is_valid = false;
        if (out.size() < kMaxStreamEventSize) {
            return 0;
        }
        last_event_ = pick_event();
        device_time_us_ += 1U + prng_.below(5000U);  // wraps (unsigned), on purpose
        switch (last_event_) {
            case StreamEvent::valid_pose:
                expected = ExpectedEmMessage{};
                expected.type = protocol::EmTrackerMessageType::pose;
                expected.pose = make_pose();
                is_valid = true;
                return protocol::encode_em_pose(expected.pose, out);
            case StreamEvent::valid_tip_force:
                expected = ExpectedEmMessage{};
                expected.type = protocol::EmTrackerMessageType::tip_force;
                expected.tip_force = make_tip_force();
                is_valid = true;
                return protocol::encode_tip_force(expected.tip_force, out);
            case StreamEvent::noise: return write_noise(out);
            case StreamEvent::corrupted_frame: {
                const std::size_t size = write_any_frame(out);
                // One byte after the sync changed: type -> unknown type / bad length, length ->
                // bad length, payload or CRC -> bad checksum (CRC-16 catches every 1-byte error).
                const std::size_t index = 2U + prng_.below(static_cast<std::uint32_t>(size - 2U));
                out[index] = static_cast<std::uint8_t>(out[index] ^ (1U + prng_.below(255U)));
                return size;
            }
            case StreamEvent::truncated_frame: {
                const std::size_t size = write_any_frame(out);
                return 1U + prng_.below(static_cast<std::uint32_t>(size - 1U));
            }
            case StreamEvent::fake_header:
            default: {
                // A sync, a known type (or not) and a length that cannot be right.
                out[0] = protocol::kEmTrackerSync0;
                out[1] = protocol::kEmTrackerSync1;
                const std::uint32_t variant = prng_.below(3U);
                out[2] = variant == 2U ? static_cast<std::uint8_t>(0x80U | prng_.byte())
                                       : static_cast<std::uint8_t>(1U + variant);
                out[3] = static_cast<std::uint8_t>(0xC0U | prng_.byte());  // >= 192: huge
                return 4;
            }
        }
    }

    [[nodiscard]] StreamEvent last_event() const noexcept { return last_event_; }
    TestPrng& prng() noexcept { return prng_; }

private:
    StreamEvent pick_event() noexcept {
        const std::uint32_t roll = prng_.below(100U);
        if (!hostile_) {
            return roll < 75U ? StreamEvent::valid_pose : StreamEvent::valid_tip_force;
        }
        if (roll < 40U) {
            return StreamEvent::valid_pose;
        }
        if (roll < 55U) {
            return StreamEvent::valid_tip_force;
        }
        if (roll < 70U) {
            return StreamEvent::noise;
        }
        if (roll < 85U) {
            return StreamEvent::corrupted_frame;
        }
        if (roll < 95U) {
            return StreamEvent::truncated_frame;
        }
        return StreamEvent::fake_header;
    }

    protocol::EmPoseMessage make_pose() noexcept {
        // Unit quaternions in Q2.14 (w, x, y, z): identity, 90° about x / y / z, 180° about z,
        // 120° about (1,1,1), 60° about x, and an arbitrary one (0.6, 0.4, 0.3, 0.6245: norm² = 1 - 2e-6).
        constexpr std::array<std::array<std::int16_t, 4>, 8> kUnitQuaternions{{
            {16384, 0, 0, 0},
            {11585, 11585, 0, 0},
            {11585, 0, 11585, 0},
            {11585, 0, 0, 11585},
            {0, 0, 0, 16384},
            {8192, 8192, 8192, 8192},
            {14189, 8192, 0, 0},
            {9830, 6554, 4915, 10232},
        }};
        protocol::EmPoseMessage message;
        message.device_time_us = device_time_us_;
        message.sensor_id = static_cast<std::uint8_t>(prng_.below(4U));
        message.status = 0;
        for (std::int32_t& coordinate : message.position_um) {
            coordinate = prng_.symmetric(900'000);
        }
        const auto& q = kUnitQuaternions[prng_.below(8U)];
        const std::uint32_t signs = prng_.next();
        for (std::size_t i = 0; i < 4U; ++i) {
            const bool negate = ((signs >> i) & 1U) != 0U;
            message.orientation_q14[i] = negate ? static_cast<std::int16_t>(-q[i]) : q[i];
        }
        return message;
    }

    protocol::TipForceMessage make_tip_force() noexcept {
        protocol::TipForceMessage message;
        message.device_time_us = device_time_us_;
        message.status = 0;
        for (std::int16_t& component : message.force_mN) {
            component = static_cast<std::int16_t>(prng_.symmetric(20'000));
        }
        return message;
    }

    std::size_t write_noise(std::span<std::uint8_t> out) noexcept {
        const std::size_t size = 1U + prng_.below(24U);
        for (std::size_t i = 0; i < size; ++i) {
            const std::uint32_t roll = prng_.below(100U);
            out[i] = roll < 25U ? protocol::kEmTrackerSync0
                                : (roll < 35U ? protocol::kEmTrackerSync1 : prng_.byte());
        }
        return size;
    }

    /// A well-formed frame whose message is NOT in the expected list (used to corrupt/truncate).
    std::size_t write_any_frame(std::span<std::uint8_t> out) noexcept {
        if (prng_.below(3U) == 0U) {
            return protocol::encode_tip_force(make_tip_force(), out);
        }
        return protocol::encode_em_pose(make_pose(), out);
    }

    TestPrng prng_;
    bool hostile_;
    std::uint32_t device_time_us_{0xFFF0'0000U};  // 1.05 s before the wrap
    StreamEvent last_event_{StreamEvent::noise};
};

/// Fills `stream` with up to `events` events (stops early when the next might not fit) and
/// `expected` with the valid messages (stops when full).  Returns the stream size; sets the
/// number of expected messages.
inline std::size_t generate_em_tracker_stream(EmTrackerStreamGenerator& generator,
                                              std::span<std::uint8_t> stream,
                                              std::span<ExpectedEmMessage> expected,
                                              std::size_t events,
                                              std::size_t& expected_count) noexcept {
    std::size_t size = 0;
    expected_count = 0;
    for (std::size_t event = 0; event < events; ++event) {
        if (stream.size() - size < kMaxStreamEventSize || expected_count == expected.size()) {
            break;
        }
        ExpectedEmMessage message;
        bool is_valid = false;
        size += generator.next(stream.subspan(size), message, is_valid);
        if (is_valid) {
            expected[expected_count] = message;
            ++expected_count;
        }
    }
    return size;
}

}  // namespace scopekin::test
