// Q16.16 fixed-point scalar of the firmware.
//
// Format
// ------
// `Q16_16` stores a real number x as the two's-complement int32 raw value r = round(x * 2^16):
// 1 sign bit, 15 integer bits, 16 fraction bits.
//   range       [-32768, 32767.9999847]  (raw INT32_MIN .. INT32_MAX)
//   resolution  2^-16 = 1.52587890625e-5
// In the firmware's units (mm, N, N·mm, s) that is ±32.7 m with 15 nm steps, ±32.7 kN with
// 15 µN steps, ±32.7 N·m with 15 µN·mm steps, and ±9.1 h with 15 µs steps.  Every physical
// quantity must still get its own written range analysis where it is introduced.
//
// Scaling and overflow behaviour (CMSIS-DSP style)
// ------------------------------------------------
// * add_sat / sub_sat / neg_sat: exact in 64 bits, then saturated to [INT32_MIN, INT32_MAX] raw.
//   No rounding is involved.  neg_sat(min()) == max().
// * mul_sat: the 32x32 -> 64-bit product is exact and in Q32.32 (62 magnitude bits at most, one
//   guard bit); it is shifted right by 16 with rounding to nearest, ties away from zero
//   ((|p| + 2^15) >> 16 on the magnitude, so the rounding is symmetric about zero), and the result
//   is saturated to Q16.16.  Round-half-away is chosen over half-to-even because it is a single
//   add-and-shift on the magnitude and is sign-symmetric; both are deterministic, which is what
//   bit-identical results on x86-64, aarch64 and Cortex-M4 require.
// * dot3_sat: three exact Q32.32 products (64-bit), accumulated in a 64-bit accumulator that
//   saturates symmetrically at ±(2^63 - 1); one rounding (as mul_sat) and one saturation at the
//   end.  For three terms the saturating accumulator gives the correctly rounded, correctly
//   saturated result of the exact sum: any accumulator saturation means |sum| >= 2^62, far beyond
//   the Q16.16 range (2^47 in Q32.32), and the remaining product (|p| <= 2^62) cannot bring it
//   back across zero into range.
// * from_int: exact for |n| <= 32767 (and -32768), saturated outside.
// * from_ratio(num, den): round(num / den * 2^16), nearest, ties away from zero, saturated;
//   den == 0 saturates towards the sign of num (0/0 gives 0).  Meant for constants.
// * to_int: nearest integer, ties away from zero (so it is exact for every representable value).
// No operation has undefined behaviour for any input; none divides at run time except from_ratio.
// No floating point is used, so results are identical on every target.
#pragma once

#include <array>
#include <compare>
#include <cstdint>
#include <limits>

namespace scopekin::fixed_point {

class Q16_16 {
public:
    using Raw = std::int32_t;
    static constexpr int fraction_bits = 16;
    static constexpr Raw one_raw = Raw{1} << fraction_bits;

    constexpr Q16_16() noexcept = default;

    [[nodiscard]] static constexpr Q16_16 from_raw(Raw raw) noexcept { return Q16_16{raw}; }
    [[nodiscard]] static constexpr Q16_16 from_int(std::int32_t value) noexcept;
    [[nodiscard]] static constexpr Q16_16 from_ratio(std::int32_t numerator,
                                                     std::int32_t denominator) noexcept;
    [[nodiscard]] static constexpr Q16_16 max() noexcept {
        return Q16_16{std::numeric_limits<Raw>::max()};
    }
    [[nodiscard]] static constexpr Q16_16 min() noexcept {
        return Q16_16{std::numeric_limits<Raw>::min()};
    }

    [[nodiscard]] constexpr Raw raw() const noexcept { return raw_; }
    [[nodiscard]] constexpr std::int32_t to_int() const noexcept;

    friend constexpr bool operator==(Q16_16, Q16_16) noexcept = default;
    friend constexpr std::strong_ordering operator<=>(Q16_16, Q16_16) noexcept = default;

private:
    constexpr explicit Q16_16(Raw raw) noexcept : raw_{raw} {}
    Raw raw_{0};
};

namespace detail {

[[nodiscard]] constexpr std::int32_t saturate_to_int32(std::int64_t value) noexcept {
    constexpr std::int64_t hi = std::numeric_limits<std::int32_t>::max();
    constexpr std::int64_t lo = std::numeric_limits<std::int32_t>::min();
    return static_cast<std::int32_t>(value > hi ? hi : (value < lo ? lo : value));
}

/// value / 2^shift rounded to nearest, ties away from zero.  Requires 1 <= shift <= 62 and
/// value != INT64_MIN (callers keep |value| <= 2^63 - 1).  Works on the magnitude m:
/// floor(m / 2^shift) plus the first discarded bit, i.e. (m + 2^(shift-1)) >> shift without the
/// intermediate sum (which could overflow for m close to 2^63).
[[nodiscard]] constexpr std::int64_t rounding_shift_right(std::int64_t value, int shift) noexcept {
    const std::int64_t magnitude = value >= 0 ? value : -value;
    const std::int64_t rounded = (magnitude >> shift) + ((magnitude >> (shift - 1)) & 1);
    return value >= 0 ? rounded : -rounded;
}

}  // namespace detail

constexpr Q16_16 Q16_16::from_int(std::int32_t value) noexcept {
    return Q16_16{detail::saturate_to_int32(std::int64_t{value} * one_raw)};
}

constexpr Q16_16 Q16_16::from_ratio(std::int32_t numerator, std::int32_t denominator) noexcept {
    if (denominator == 0) {
        return numerator > 0 ? max() : (numerator < 0 ? min() : Q16_16{});
    }
    const bool negative = (numerator < 0) != (denominator < 0);
    const std::int64_t n = numerator < 0 ? -std::int64_t{numerator} : std::int64_t{numerator};
    const std::int64_t d = denominator < 0 ? -std::int64_t{denominator} : std::int64_t{denominator};
    // |num| * 2^16 <= 2^47: no overflow.  Adding floor(d/2) before the floor division rounds to
    // nearest with ties away from zero (ties only exist for even d).
    const std::int64_t magnitude = (n * one_raw + d / 2) / d;
    return Q16_16{detail::saturate_to_int32(negative ? -magnitude : magnitude)};
}

constexpr std::int32_t Q16_16::to_int() const noexcept {
    return static_cast<std::int32_t>(detail::rounding_shift_right(raw_, fraction_bits));
}

[[nodiscard]] constexpr Q16_16 add_sat(Q16_16 a, Q16_16 b) noexcept {
    return Q16_16::from_raw(detail::saturate_to_int32(std::int64_t{a.raw()} + b.raw()));
}

[[nodiscard]] constexpr Q16_16 sub_sat(Q16_16 a, Q16_16 b) noexcept {
    return Q16_16::from_raw(detail::saturate_to_int32(std::int64_t{a.raw()} - b.raw()));
}

[[nodiscard]] constexpr Q16_16 neg_sat(Q16_16 a) noexcept {
    return Q16_16::from_raw(detail::saturate_to_int32(-std::int64_t{a.raw()}));
}

[[nodiscard]] constexpr Q16_16 mul_sat(Q16_16 a, Q16_16 b) noexcept {
    const std::int64_t product = std::int64_t{a.raw()} * b.raw();  // Q32.32, |p| <= 2^62
    return Q16_16::from_raw(
        detail::saturate_to_int32(detail::rounding_shift_right(product, Q16_16::fraction_bits)));
}

/// Saturating arithmetic operators, identical to the named functions (so generic kernels can be
/// written once for `double` and for Q16_16).
[[nodiscard]] constexpr Q16_16 operator+(Q16_16 a, Q16_16 b) noexcept { return add_sat(a, b); }
[[nodiscard]] constexpr Q16_16 operator-(Q16_16 a, Q16_16 b) noexcept { return sub_sat(a, b); }
[[nodiscard]] constexpr Q16_16 operator-(Q16_16 a) noexcept { return neg_sat(a); }
[[nodiscard]] constexpr Q16_16 operator*(Q16_16 a, Q16_16 b) noexcept { return mul_sat(a, b); }

using Q16_16Vec3 = std::array<Q16_16, 3>;

/// a·b for 3-vectors: exact 64-bit products, saturating 64-bit accumulation, one rounding and one
/// saturation (see "Scaling and overflow behaviour" above).  Implemented with Eigen fixed-size
/// integer vectors (no heap).
[[nodiscard]] Q16_16 dot3_sat(const Q16_16Vec3& a, const Q16_16Vec3& b) noexcept;

}  // namespace scopekin::fixed_point
