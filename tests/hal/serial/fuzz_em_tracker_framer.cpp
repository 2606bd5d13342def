// fuzz_em_tracker_framer.cpp — libFuzzer entry point for the EM-tracker framer
// (firmware/protocol/em_tracker/em_tracker_frame.hpp).
//
// Input: byte 0 seeds the chunk sizes, the rest is the wire stream.  The stream is pushed twice:
// byte by byte, and in pseudo-random chunks of 1..80 bytes — or, when bit 7 of byte 0 is set,
// 1..400 bytes, more than the 256-byte ring holds, so push() refuses bytes and the caller re-pushes
// them after popping.  Invariants (any violation is __builtin_trap()):
//   * every frame handed out has a known type and that type's payload length, decodes (and the
//     other type's decoder refuses it), and re-encodes to exactly the 17 or 32 bytes of the input
//     that the byte accounting says it came from — sync, header, payload and the CRC that was on
//     the wire: the framer never invents, shifts or mis-checks a frame;
//   * after pop() returns false fewer than kEmTrackerMaxFrameSize bytes are buffered;
//   * bytes accepted == bytes of popped frames + bytes_discarded + buffered() at every step;
//   * push() takes min(offered, free room) bytes, never 0 when there is room;
//   * the output (frames, in order) and every counter but buffer_overflows do not depend on how
//     the stream was split.
// Built as scopekin_fuzz_em_tracker_framer and run by CTest as fuzz.em_tracker_framer in the
// `fuzz` preset (tests/fuzz/CMakeLists.txt), on a copy of tests/hal/serial/fuzz_corpus/.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace {

using scopekin::protocol::EmTrackerFrame;
using scopekin::protocol::EmTrackerFramer;
using scopekin::protocol::EmTrackerMessageType;
namespace protocol = scopekin::protocol;

void check(bool condition) {
    if (!condition) {
        __builtin_trap();
    }
}

/// What a framer produced: a running digest of the frames, in order, and their byte count.
struct Output {
    std::size_t frames{0};
    std::size_t frame_bytes{0};
    std::uint32_t digest{0x811C9DC5U};  // FNV-1a over type, length, payload of every frame

    void add(const EmTrackerFrame& frame) {
        ++frames;
        frame_bytes += frame.payload_length + protocol::kEmTrackerOverhead;
        mix(static_cast<std::uint8_t>(frame.type));
        mix(frame.payload_length);
        for (std::size_t i = 0; i < frame.payload_length; ++i) {
            mix(frame.payload[i]);
        }
    }
    void mix(std::uint8_t byte) { digest = (digest ^ byte) * 0x01000193U; }
};

/// Checks a popped frame against the input: it must be a real frame of the stream, byte for
/// byte (sync, header, payload and the CRC that was on the wire), ending exactly where the byte
/// accounting says the framer has consumed up to (`end`: bytes of frames + bytes discarded).
void check_frame(const EmTrackerFrame& frame, std::span<const std::uint8_t> stream,
                 std::size_t end) {
    const auto type = static_cast<std::uint8_t>(frame.type);
    const std::size_t size = protocol::em_tracker_payload_size(type);
    check(size != 0U);
    check(frame.payload_length == size);
    std::array<std::uint8_t, protocol::kEmTrackerMaxFrameSize> encoded{};
    std::size_t encoded_size = 0;
    if (frame.type == EmTrackerMessageType::pose) {
        protocol::EmPoseMessage message;
        check(protocol::decode_em_pose(frame, message));
        protocol::TipForceMessage other;
        check(!protocol::decode_tip_force(frame, other));
        encoded_size = protocol::encode_em_pose(message, encoded);
    } else {
        protocol::TipForceMessage message;
        check(protocol::decode_tip_force(frame, message));
        protocol::EmPoseMessage other;
        check(!protocol::decode_em_pose(frame, other));
        encoded_size = protocol::encode_tip_force(message, encoded);
    }
    // decode + encode reproduces the wire bytes, CRC included.
    check(encoded_size == size + protocol::kEmTrackerOverhead);
    check(end >= encoded_size && end <= stream.size());
    for (std::size_t i = 0; i < encoded_size; ++i) {
        check(stream[end - encoded_size + i] == encoded[i]);
    }
}

void pop_all(EmTrackerFramer& framer, Output& output, std::span<const std::uint8_t> stream,
             std::size_t accepted) {
    EmTrackerFrame frame;
    std::size_t pops = 0;
    while (framer.pop(frame)) {
        output.add(frame);
        check_frame(frame, stream, output.frame_bytes + framer.counters().bytes_discarded);
        ++pops;
        check(pops <= protocol::kEmTrackerFramerCapacity / protocol::kEmTrackerMinFrameSize);
    }
    check(framer.buffered() < protocol::kEmTrackerMaxFrameSize);
    check(accepted == output.frame_bytes + framer.counters().bytes_discarded + framer.buffered());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0U) {
        return 0;
    }
    const std::uint8_t control = data[0];
    const std::span<const std::uint8_t> stream{data + 1, size - 1U};

    // 1. Byte by byte.
    EmTrackerFramer single;
    Output single_output;
    std::size_t single_accepted = 0;
    for (const std::uint8_t byte : stream) {
        check(single.push(byte));
        ++single_accepted;
        pop_all(single, single_output, stream, single_accepted);
    }

    // 2. In pseudo-random chunks, oversized ones included when bit 7 of the control byte is set.
    EmTrackerFramer chunked;
    Output chunked_output;
    std::size_t chunked_accepted = 0;
    std::uint32_t prng = 0x9E3779B9U ^ (std::uint32_t{control} * 0x01000193U);
    const std::uint32_t max_chunk = (control & 0x80U) != 0U ? 400U : 80U;
    std::size_t offset = 0;
    while (offset < stream.size()) {
        prng ^= prng << 13U;
        prng ^= prng >> 17U;
        prng ^= prng << 5U;
        std::size_t chunk = 1U + prng % max_chunk;
        chunk = chunk < stream.size() - offset ? chunk : stream.size() - offset;
        const std::size_t room = protocol::kEmTrackerFramerCapacity - chunked.buffered();
        const std::uint32_t overflows_before = chunked.counters().buffer_overflows;
        const std::size_t taken = chunked.push(stream.subspan(offset, chunk));
        check(taken == (chunk < room ? chunk : room));
        check(taken > 0U);  // pop_all below always leaves room
        check(chunked.counters().buffer_overflows == overflows_before + (taken < chunk ? 1U : 0U));
        offset += taken;  // refused bytes are pushed again next time
        chunked_accepted += taken;
        pop_all(chunked, chunked_output, stream, chunked_accepted);
    }

    // 3. The split does not matter.
    check(single_accepted == stream.size() && chunked_accepted == stream.size());
    check(single_output.frames == chunked_output.frames);
    check(single_output.digest == chunked_output.digest);
    const auto& a = single.counters();
    const auto& b = chunked.counters();
    check(a.frames_ok == single_output.frames);
    check(a.frames_ok == b.frames_ok && a.bad_checksum == b.bad_checksum &&
          a.bad_length == b.bad_length && a.unknown_type == b.unknown_type &&
          a.bytes_discarded == b.bytes_discarded);
    check(single.buffered() == chunked.buffered());
    check(a.buffer_overflows == 0U);
    return 0;
}
