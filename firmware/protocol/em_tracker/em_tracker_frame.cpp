// em_tracker_frame.cpp — encoder, decoder and framer of the EM-tracker serial protocol
// (em_tracker_serial.md).  Little-endian fields are assembled byte by byte, so the code is the
// same on every target whatever its endianness or alignment rules.
#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace scopekin::protocol {
namespace {

// --- little-endian field writers / readers over a fixed payload ------------------------------------

struct PayloadWriter {
    std::array<std::uint8_t, kEmTrackerMaxPayloadSize> bytes{};
    std::size_t size{0};

    void u8(std::uint8_t value) noexcept {
        if (size < bytes.size()) {
            bytes[size] = value;
            ++size;
        }
    }
    void u16(std::uint16_t value) noexcept {
        u8(static_cast<std::uint8_t>(value & 0xFFU));
        u8(static_cast<std::uint8_t>(value >> 8U));
    }
    void u32(std::uint32_t value) noexcept {
        u16(static_cast<std::uint16_t>(value & 0xFFFFU));
        u16(static_cast<std::uint16_t>(value >> 16U));
    }
    // Two's complement on the wire: the conversion to unsigned is modular (well defined).
    void i16(std::int16_t value) noexcept { u16(static_cast<std::uint16_t>(value)); }
    void i32(std::int32_t value) noexcept { u32(static_cast<std::uint32_t>(value)); }
};

struct PayloadReader {
    const EmTrackerFrame& frame;
    std::size_t offset{0};

    [[nodiscard]] std::uint8_t u8() noexcept {
        const std::uint8_t value = offset < frame.payload.size() ? frame.payload[offset] : 0U;
        ++offset;
        return value;
    }
    [[nodiscard]] std::uint16_t u16() noexcept {
        const std::uint16_t low = u8();
        const std::uint16_t high = u8();
        return static_cast<std::uint16_t>(low | static_cast<std::uint16_t>(high << 8U));
    }
    [[nodiscard]] std::uint32_t u32() noexcept {
        const std::uint32_t low = u16();
        const std::uint32_t high = u16();
        return low | (high << 16U);
    }
    // Unsigned -> signed of the same width: C++20 defines it as modular (two's complement).
    [[nodiscard]] std::int16_t i16() noexcept { return static_cast<std::int16_t>(u16()); }
    [[nodiscard]] std::int32_t i32() noexcept { return static_cast<std::int32_t>(u32()); }
};

}  // namespace

std::size_t encode_em_tracker_frame(std::uint8_t type, std::span<const std::uint8_t> payload,
                                    std::span<std::uint8_t> out) noexcept {
    if (payload.size() > 255U || out.size() < payload.size() + kEmTrackerOverhead) {
        return 0;
    }
    const auto length = static_cast<std::uint8_t>(payload.size());
    out[0] = kEmTrackerSync0;
    out[1] = kEmTrackerSync1;
    out[2] = type;
    out[3] = length;
    for (std::size_t i = 0; i < payload.size(); ++i) {  // bound: 255
        out[kEmTrackerHeaderSize + i] = payload[i];
    }
    const std::uint16_t crc =
        em_tracker_crc16(std::span<const std::uint8_t>{out.data() + 2, payload.size() + 2U});
    out[kEmTrackerHeaderSize + payload.size()] = static_cast<std::uint8_t>(crc & 0xFFU);
    out[kEmTrackerHeaderSize + payload.size() + 1U] = static_cast<std::uint8_t>(crc >> 8U);
    return payload.size() + kEmTrackerOverhead;
}

std::size_t encode_em_pose(const EmPoseMessage& message, std::span<std::uint8_t> out) noexcept {
    PayloadWriter writer;
    writer.u32(message.device_time_us);
    writer.u8(message.sensor_id);
    writer.u8(message.status);
    for (const std::int32_t coordinate : message.position_um) {  // bound: 3
        writer.i32(coordinate);
    }
    for (const std::int16_t component : message.orientation_q14) {  // bound: 4
        writer.i16(component);
    }
    static_assert(4 + 1 + 1 + 3 * 4 + 4 * 2 == kEmPosePayloadSize);
    return encode_em_tracker_frame(static_cast<std::uint8_t>(EmTrackerMessageType::pose),
                                   std::span<const std::uint8_t>{writer.bytes.data(), writer.size},
                                   out);
}

std::size_t encode_tip_force(const TipForceMessage& message, std::span<std::uint8_t> out) noexcept {
    PayloadWriter writer;
    writer.u32(message.device_time_us);
    writer.u8(message.status);
    for (const std::int16_t component : message.force_mN) {  // bound: 3
        writer.i16(component);
    }
    static_assert(4 + 1 + 3 * 2 == kTipForcePayloadSize);
    return encode_em_tracker_frame(static_cast<std::uint8_t>(EmTrackerMessageType::tip_force),
                                   std::span<const std::uint8_t>{writer.bytes.data(), writer.size},
                                   out);
}

bool decode_em_pose(const EmTrackerFrame& frame, EmPoseMessage& out) noexcept {
    if (frame.type != EmTrackerMessageType::pose || frame.payload_length != kEmPosePayloadSize) {
        return false;
    }
    PayloadReader reader{frame};
    EmPoseMessage message;
    message.device_time_us = reader.u32();
    message.sensor_id = reader.u8();
    message.status = reader.u8();
    for (std::int32_t& coordinate : message.position_um) {  // bound: 3
        coordinate = reader.i32();
    }
    for (std::int16_t& component : message.orientation_q14) {  // bound: 4
        component = reader.i16();
    }
    out = message;
    return true;
}

bool decode_tip_force(const EmTrackerFrame& frame, TipForceMessage& out) noexcept {
    if (frame.type != EmTrackerMessageType::tip_force ||
        frame.payload_length != kTipForcePayloadSize) {
        return false;
    }
    PayloadReader reader{frame};
    TipForceMessage message;
    message.device_time_us = reader.u32();
    message.status = reader.u8();
    for (std::int16_t& component : message.force_mN) {  // bound: 3
        component = reader.i16();
    }
    out = message;
    return true;
}

// --- Framer -----------------------------------------------------------------------------------------

std::size_t EmTrackerFramer::push(std::span<const std::uint8_t> bytes) noexcept {
    const std::size_t room = kEmTrackerFramerCapacity - size_;
    const std::size_t taken = bytes.size() < room ? bytes.size() : room;
    for (std::size_t i = 0; i < taken; ++i) {  // bound: kEmTrackerFramerCapacity
        buffer_[(head_ + size_) & kMask] = bytes[i];
        ++size_;
    }
    if (taken < bytes.size()) {
        ++counters_.buffer_overflows;
    }
    return taken;
}

bool EmTrackerFramer::push(std::uint8_t byte) noexcept {
    return push(std::span<const std::uint8_t>{&byte, 1}) == 1U;
}

void EmTrackerFramer::discard(std::size_t count) noexcept {
    const std::size_t dropped = count < size_ ? count : size_;
    head_ = (head_ + dropped) & kMask;
    size_ -= dropped;
}

void EmTrackerFramer::clear() noexcept {
    counters_.bytes_discarded += static_cast<std::uint32_t>(size_);
    discard(size_);
}

bool EmTrackerFramer::pop(EmTrackerFrame& frame) noexcept {
    // Every pass either returns or discards one byte, so size_ + 1 passes always suffice.
    for (std::size_t pass = 0; pass <= kEmTrackerFramerCapacity; ++pass) {  // bound: capacity + 1
        if (size_ == 0U) {
            return false;
        }
        // Each branch below either returns (a frame, or "wait for more bytes") or falls through
        // to the rejection at the end of the pass.
        if (at(0) != kEmTrackerSync0) {
            // not a frame start
        } else if (size_ < 2U) {
            return false;
        } else if (at(1) != kEmTrackerSync1) {
            // 0xA5 without 0x5A
        } else if (size_ < 3U) {
            return false;
        } else {
            const std::uint8_t type = at(2);
            const std::size_t expected_length = em_tracker_payload_size(type);
            if (expected_length == 0U) {
                ++counters_.unknown_type;
            } else if (size_ < kEmTrackerHeaderSize) {
                return false;
            } else if (at(3) != expected_length) {
                ++counters_.bad_length;
            } else if (size_ < expected_length + kEmTrackerOverhead) {
                return false;  // a candidate that is still arriving
            } else {
                // CRC over type, length, payload: offsets 2 .. 3 + length.
                std::uint16_t crc = kEmTrackerCrcInit;
                for (std::size_t i = 2; i < kEmTrackerHeaderSize + expected_length; ++i) {  // <= 28
                    crc = em_tracker_crc16_update(crc, at(i));
                }
                const std::size_t crc_offset = kEmTrackerHeaderSize + expected_length;
                const auto received = static_cast<std::uint16_t>(
                    at(crc_offset) | static_cast<std::uint16_t>(at(crc_offset + 1U) << 8U));
                if (crc != received) {
                    ++counters_.bad_checksum;
                } else {
                    frame.type = static_cast<EmTrackerMessageType>(type);
                    frame.payload_length = static_cast<std::uint8_t>(expected_length);
                    frame.payload = {};
                    for (std::size_t i = 0; i < expected_length; ++i) {  // <= 26
                        frame.payload[i] = at(kEmTrackerHeaderSize + i);
                    }
                    discard(expected_length + kEmTrackerOverhead);
                    ++counters_.frames_ok;
                    return true;
                }
            }
        }
        // Rejected: only the first byte goes, a valid frame may start at the very next one.
        ++counters_.bytes_discarded;
        discard(1);
    }
    return false;  // not reached: the buffer empties within capacity + 1 passes
}

}  // namespace scopekin::protocol
