// can_signal.hpp — one signal of a CAN message as the DBC defines it, and the integer arithmetic
// that packs it into / out of a frame's 8 data bytes.
//
// Layout: little-endian ("Intel", `@1` in the DBC): bit k of the signal is bit (start_bit + k) of
// the frame, counting bit 0 = LSB of data[0].  Signed signals are two's complement over
// bit_length bits.  physical = raw * factor_numerator / factor_denominator (offset 0 for every
// signal of scopekin.dbc).
//
// Scaling and overflow (raw <-> Q16.16, the firmware's only physical type):
//   raw_to_q16: q = raw * num * 2^16 / den, rounded to nearest (ties away from zero).  |raw| <
//     2^32, num <= 2^8, so |raw * num * 2^16| < 2^56: exact in int64.  Results beyond int32
//     (e.g. an insertion of 40 m in a 24-bit signal) saturate and set `saturated`.
//   q16_to_raw: raw = q * den / (num * 2^16), rounded to nearest.  |q| < 2^31, den <= 2^16:
//     exact in int64.  Results beyond the signal's raw range saturate to it and set `saturated`.
//   Both are pure integer operations: bit-identical on every target.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include "fixed_point/q_format.hpp"
#include "hal/can_bus.hpp"

namespace scopekin::protocol {

struct CanSignal {
    const char* name;         ///< as in scopekin.dbc
    std::uint8_t start_bit;   ///< 0..63
    std::uint8_t bit_length;  ///< 1..32
    bool is_signed;
    std::int32_t factor_numerator;  ///< physical = raw * numerator / denominator
    std::int32_t factor_denominator;
};

[[nodiscard]] constexpr std::int64_t raw_min(const CanSignal& signal) {
    return signal.is_signed ? -(std::int64_t{1} << (signal.bit_length - 1U)) : 0;
}
[[nodiscard]] constexpr std::int64_t raw_max(const CanSignal& signal) {
    return signal.is_signed ? (std::int64_t{1} << (signal.bit_length - 1U)) - 1
                            : (std::int64_t{1} << signal.bit_length) - 1;
}

/// The signal's raw value from `data` (sign-extended if signed).
[[nodiscard]] constexpr std::int64_t read_raw(const std::array<std::uint8_t, 8>& data,
                                              const CanSignal& signal) {
    std::uint64_t bits = 0;
    for (std::uint32_t k = 0; k < signal.bit_length; ++k) {  // bound: bit_length <= 32
        const std::uint32_t bit = signal.start_bit + k;
        const std::uint32_t byte_value = data[bit / 8U];
        if (((byte_value >> (bit % 8U)) & 1U) != 0U) {
            bits |= std::uint64_t{1} << k;
        }
    }
    if (signal.is_signed && ((bits >> (signal.bit_length - 1U)) & 1U) != 0U) {
        return static_cast<std::int64_t>(bits) - (std::int64_t{1} << signal.bit_length);
    }
    return static_cast<std::int64_t>(bits);
}

/// Writes `raw` (clamped to the signal's range) into `data`; other bits are untouched.
constexpr void write_raw(std::array<std::uint8_t, 8>& data, const CanSignal& signal,
                         std::int64_t raw) {
    const std::int64_t clamped =
        raw < raw_min(signal) ? raw_min(signal) : (raw > raw_max(signal) ? raw_max(signal) : raw);
    const auto bits = static_cast<std::uint64_t>(clamped);   // two's complement, low bits kept
    for (std::uint32_t k = 0; k < signal.bit_length; ++k) {  // bound: bit_length <= 32
        const std::uint32_t bit = signal.start_bit + k;
        const auto mask = static_cast<std::uint8_t>(1U << (bit % 8U));
        if (((bits >> k) & 1U) != 0U) {
            data[bit / 8U] = static_cast<std::uint8_t>(data[bit / 8U] | mask);
        } else {
            data[bit / 8U] = static_cast<std::uint8_t>(data[bit / 8U] & ~mask);
        }
    }
}

/// Physical value of `raw` in Q16.16 (see "Scaling and overflow").
[[nodiscard]] constexpr fixed_point::Q16_16 raw_to_q16(std::int64_t raw, const CanSignal& signal,
                                                       bool& saturated) {
    const std::int64_t numerator = raw * signal.factor_numerator * fixed_point::Q16_16::one_raw;
    const std::int32_t q =
        fixed_point::detail::divide_round_saturate(numerator, signal.factor_denominator);
    // The rounded quotient before saturation (|numerator| < 2^56, so 2|numerator| + d fits):
    // magnitude rounded half up = ties away from zero, as divide_round_saturate rounds.
    const std::int64_t denominator = signal.factor_denominator;
    const std::int64_t magnitude = numerator >= 0 ? numerator : -numerator;
    const std::int64_t rounded_magnitude = (2 * magnitude + denominator) / (2 * denominator);
    const std::int64_t rounded = numerator >= 0 ? rounded_magnitude : -rounded_magnitude;
    if (rounded > std::numeric_limits<std::int32_t>::max() ||
        rounded < std::numeric_limits<std::int32_t>::min()) {
        saturated = true;
    }
    return fixed_point::Q16_16::from_raw(q);
}

/// Raw value of the physical `value` (see "Scaling and overflow").
[[nodiscard]] constexpr std::int64_t q16_to_raw(fixed_point::Q16_16 value, const CanSignal& signal,
                                                bool& saturated) {
    const std::int64_t raw = fixed_point::detail::divide_round_saturate(
        std::int64_t{value.raw()} * signal.factor_denominator,
        std::int64_t{signal.factor_numerator} * fixed_point::Q16_16::one_raw);
    if (raw < raw_min(signal)) {
        saturated = true;
        return raw_min(signal);
    }
    if (raw > raw_max(signal)) {
        saturated = true;
        return raw_max(signal);
    }
    return raw;
}

}  // namespace scopekin::protocol
