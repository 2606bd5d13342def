// em_tracker_frame.hpp — the test bench's serial EM-tracker protocol: CRC, encoder, framer.
//
// The wire format (sync bytes, message types, units, what the receiver does with malformed
// input) is specified in em_tracker_serial.md next to this file; the constants below are that
// document's numbers.  This layer knows bytes and raw wire integers only; turning frames into
// validated, time-stamped samples in mm / N (Q16.16) is the driver's job
// (firmware/drivers/em_tracker_driver.hpp).
//
// Firmware rules: no heap, no exceptions, fixed-size storage (the framer owns a
// kEmTrackerFramerCapacity-byte ring), every loop bounded by a compile-time capacity or by the
// length of the caller's span.  Nothing here can crash, hang or read out of bounds for any input.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace scopekin::protocol {

// --- Frame layout (em_tracker_serial.md §2) -------------------------------------------------------
inline constexpr std::uint8_t kEmTrackerSync0 = 0xA5U;
inline constexpr std::uint8_t kEmTrackerSync1 = 0x5AU;
inline constexpr std::size_t kEmTrackerHeaderSize = 4;  ///< sync0, sync1, type, payload length
inline constexpr std::size_t kEmTrackerCrcSize = 2;     ///< CRC-16/CCITT-FALSE, little-endian
inline constexpr std::size_t kEmTrackerOverhead = kEmTrackerHeaderSize + kEmTrackerCrcSize;

/// Message types (byte 2 of a frame).
enum class EmTrackerMessageType : std::uint8_t {
    pose = 0x01U,       ///< 6-DOF pose of one tracker sensor
    tip_force = 0x02U,  ///< tip contact force
};

inline constexpr std::size_t kEmPosePayloadSize = 26;    ///< see EmPoseMessage
inline constexpr std::size_t kTipForcePayloadSize = 11;  ///< see TipForceMessage
inline constexpr std::size_t kEmTrackerMaxPayloadSize = 26;
inline constexpr std::size_t kEmTrackerMaxFrameSize =
    kEmTrackerOverhead + kEmTrackerMaxPayloadSize;  // 32
inline constexpr std::size_t kEmTrackerMinFrameSize =
    kEmTrackerOverhead + kTipForcePayloadSize;  // 17

/// Payload length a message type must have; 0 for an unknown type.
[[nodiscard]] constexpr std::size_t em_tracker_payload_size(std::uint8_t type) noexcept {
    switch (type) {
        case static_cast<std::uint8_t>(EmTrackerMessageType::pose): return kEmPosePayloadSize;
        case static_cast<std::uint8_t>(EmTrackerMessageType::tip_force):
            return kTipForcePayloadSize;
        default: return 0;
    }
}

// --- CRC-16/CCITT-FALSE ----------------------------------------------------------------------------
// poly 0x1021, init 0xFFFF, not reflected, no final xor; check value crc("123456789") = 0x29B1.
// Computed over type, length and payload (not the sync bytes).  Table-driven, the 256-entry table
// (512 bytes of flash) is built at compile time.

inline constexpr std::uint16_t kEmTrackerCrcInit = 0xFFFFU;

namespace detail {

[[nodiscard]] constexpr std::array<std::uint16_t, 256> make_crc16_ccitt_table() noexcept {
    std::array<std::uint16_t, 256> table{};
    for (std::size_t i = 0; i < table.size(); ++i) {  // bound: 256
        // Unsigned int arithmetic (no promotion to signed int), 16 bits kept.
        auto crc = static_cast<unsigned>(i << 8U);
        for (int bit = 0; bit < 8; ++bit) {  // bound: 8
            crc = (crc & 0x8000U) != 0U ? ((crc << 1U) ^ 0x1021U) & 0xFFFFU : (crc << 1U) & 0xFFFFU;
        }
        table[i] = static_cast<std::uint16_t>(crc);
    }
    return table;
}

inline constexpr std::array<std::uint16_t, 256> kCrc16CcittTable = make_crc16_ccitt_table();

}  // namespace detail

/// Continues a CRC-16/CCITT-FALSE over one more byte.
[[nodiscard]] constexpr std::uint16_t em_tracker_crc16_update(std::uint16_t crc,
                                                              std::uint8_t byte) noexcept {
    const unsigned wide = crc;
    const unsigned index = ((wide >> 8U) ^ static_cast<unsigned>(byte)) & 0xFFU;
    return static_cast<std::uint16_t>(((wide << 8U) ^ detail::kCrc16CcittTable[index]) & 0xFFFFU);
}

/// CRC-16/CCITT-FALSE of `bytes` (work: bytes.size()).
[[nodiscard]] constexpr std::uint16_t em_tracker_crc16(
    std::span<const std::uint8_t> bytes, std::uint16_t crc = kEmTrackerCrcInit) noexcept {
    for (const std::uint8_t byte : bytes) {  // bound: bytes.size()
        crc = em_tracker_crc16_update(crc, byte);
    }
    return crc;
}

// --- Messages (raw wire values; em_tracker_serial.md §3) -----------------------------------------

/// Message type 0x01: one sensor's pose.
struct EmPoseMessage {
    std::uint32_t device_time_us{0};                ///< tracker clock, wraps at 2^32 µs (71.6 min)
    std::uint8_t sensor_id{0};                      ///< 0 tip, 1 20 cm, 2 handle, 3 sigmoid
    std::uint8_t status{0};                         ///< kEmStatus* bits, 0 = good
    std::array<std::int32_t, 3> position_um{};      ///< x, y, z in µm, tracker frame
    std::array<std::int16_t, 4> orientation_q14{};  ///< unit quaternion w, x, y, z; 1.0 = 16384

    friend constexpr bool operator==(const EmPoseMessage&, const EmPoseMessage&) = default;
};

/// Message type 0x02: tip contact force.
struct TipForceMessage {
    std::uint32_t device_time_us{0};         ///< force sensor clock, wraps at 2^32 µs
    std::uint8_t status{0};                  ///< kTipForceStatus* bits, 0 = good
    std::array<std::int16_t, 3> force_mN{};  ///< x, y, z in mN (z along the scope axis)

    friend constexpr bool operator==(const TipForceMessage&, const TipForceMessage&) = default;
};

/// Status bits of a pose (any bit set, reserved ones included, marks the sample unusable).
enum EmPoseStatus : std::uint8_t {
    kEmStatusOutOfMotionBox = 1U << 0U,  ///< sensor outside the field generator's volume
    kEmStatusDisconnected = 1U << 1U,    ///< sensor not plugged in / broken cable
};
/// Status bits of a tip force message.
enum TipForceStatus : std::uint8_t {
    kTipForceStatusSaturated = 1U << 0U,  ///< the sensing element is at its full scale
    kTipForceStatusNotCalibrated = 1U << 1U,
};

/// A complete frame that passed every check of the framer: known type, the type's exact payload
/// length, correct CRC.  Only the first payload_length bytes of payload are meaningful.
struct EmTrackerFrame {
    EmTrackerMessageType type{EmTrackerMessageType::pose};
    std::uint8_t payload_length{0};
    std::array<std::uint8_t, kEmTrackerMaxPayloadSize> payload{};
};

// --- Encoder (simulators, tests, a future tracker bridge) -----------------------------------------

/// Writes a frame (sync, type, length, payload, CRC) of any type byte — unknown ones included,
/// for tests — to the front of `out`.  Returns the frame size, or 0 (nothing meaningful written)
/// if payload.size() > 255 or `out` is smaller than payload.size() + kEmTrackerOverhead.
[[nodiscard]] std::size_t encode_em_tracker_frame(std::uint8_t type,
                                                  std::span<const std::uint8_t> payload,
                                                  std::span<std::uint8_t> out) noexcept;
/// A pose frame (kEmTrackerMaxFrameSize = 32 bytes); 0 if `out` is too small.
[[nodiscard]] std::size_t encode_em_pose(const EmPoseMessage& message,
                                         std::span<std::uint8_t> out) noexcept;
/// A tip force frame (17 bytes); 0 if `out` is too small.
[[nodiscard]] std::size_t encode_tip_force(const TipForceMessage& message,
                                           std::span<std::uint8_t> out) noexcept;

// --- Decoder (frame -> raw message; no range checks, those are the driver's) -----------------------

/// False if the frame is not a pose or its length is not kEmPosePayloadSize (`out` untouched).
[[nodiscard]] bool decode_em_pose(const EmTrackerFrame& frame, EmPoseMessage& out) noexcept;
/// False if the frame is not a tip force or its length is not kTipForcePayloadSize.
[[nodiscard]] bool decode_tip_force(const EmTrackerFrame& frame, TipForceMessage& out) noexcept;

// --- Framer -----------------------------------------------------------------------------------------

/// Counters since construction (they wrap at 2^32).
struct EmTrackerFramerCounters {
    std::uint32_t frames_ok{0};         ///< complete, valid frames handed out
    std::uint32_t bad_checksum{0};      ///< known type, right length, CRC mismatch
    std::uint32_t bad_length{0};        ///< known type with a length byte other than its size
    std::uint32_t unknown_type{0};      ///< sync followed by a type byte that is not 0x01/0x02
    std::uint32_t bytes_discarded{0};   ///< bytes that are not part of any valid frame
    std::uint32_t buffer_overflows{0};  ///< push() calls that could not take every byte
};

/// Ring capacity of the framer, bytes.  Any capacity >= kEmTrackerMaxFrameSize works; 256 holds
/// the driver's 128-byte reads plus a partial frame with room to spare.
inline constexpr std::size_t kEmTrackerFramerCapacity = 256;

/// Incremental framer: push bytes in, take complete, validated frames out.
///
/// Resynchronisation: frames are searched at the front of the buffer.  A byte that cannot start a
/// frame is discarded.  A candidate whose type is unknown, whose length byte is not its type's
/// size, or whose CRC is wrong loses ONLY its first sync byte and the search restarts at the next
/// byte, so a valid frame that follows garbage, or that starts inside the bytes of a corrupted or
/// truncated frame, is always found.  A type/length check failure is decided as soon as the
/// header's 4 bytes are there (a false sync with a huge length never makes the framer wait).
///
/// Work: push() is O(bytes pushed); pop() discards at least one byte per rejected candidate, so
/// one pop() does at most kEmTrackerFramerCapacity + 1 scan steps plus one CRC over at most 28
/// bytes per candidate.  After pop() returns false, fewer than kEmTrackerMaxFrameSize bytes are
/// buffered, so a caller that pops until false after every push never overflows with pushes of up
/// to kEmTrackerFramerCapacity - kEmTrackerMaxFrameSize + 1 bytes.
///
/// Byte accounting (an invariant the tests and the fuzzer check):
///   bytes accepted by push() == sum of the sizes of popped frames + bytes_discarded + buffered().
class EmTrackerFramer {
public:
    /// Appends as many of `bytes` as fit; returns how many were taken (the caller still owns the
    /// rest).  Taking fewer than bytes.size() counts one buffer overflow.
    [[nodiscard]] std::size_t push(std::span<const std::uint8_t> bytes) noexcept;
    /// One byte; false (and one buffer overflow counted) if the buffer is full.
    [[nodiscard]] bool push(std::uint8_t byte) noexcept;
    /// Takes the next valid frame out; false if no complete valid frame is buffered (yet).
    [[nodiscard]] bool pop(EmTrackerFrame& frame) noexcept;
    /// Drops every buffered byte (counted as discarded), e.g. after the port was reopened.
    void clear() noexcept;

    [[nodiscard]] std::size_t buffered() const noexcept { return size_; }
    [[nodiscard]] const EmTrackerFramerCounters& counters() const noexcept { return counters_; }

private:
    static_assert((kEmTrackerFramerCapacity & (kEmTrackerFramerCapacity - 1U)) == 0U,
                  "ring indices are masked: capacity must be a power of two");
    static_assert(kEmTrackerFramerCapacity >= kEmTrackerMaxFrameSize);
    static constexpr std::size_t kMask = kEmTrackerFramerCapacity - 1U;

    [[nodiscard]] std::uint8_t at(std::size_t offset) const noexcept {
        return buffer_[(head_ + offset) & kMask];
    }
    void discard(std::size_t count) noexcept;

    std::array<std::uint8_t, kEmTrackerFramerCapacity> buffer_{};
    std::size_t head_{0};  ///< index of the oldest buffered byte
    std::size_t size_{0};  ///< buffered bytes, <= kEmTrackerFramerCapacity
    EmTrackerFramerCounters counters_{};
};

}  // namespace scopekin::protocol
