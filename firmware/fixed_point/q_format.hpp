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
// quantity has its own written range analysis: firmware/fixed_point/RANGES.md.
//
// Scaling and overflow behaviour (CMSIS-DSP style)
// ------------------------------------------------
// Rounding: every operation that discards bits rounds to nearest, ties away from zero (rounding
// the magnitude half-up, so the rounding is symmetric about zero), and rounds ONCE, at its end.
// Round-half-away is chosen over half-to-even because it is a single add-and-shift on the
// magnitude and is sign-symmetric; both are deterministic, which is what bit-identical results on
// x86-64, aarch64 and Cortex-M4 require.  Saturation: results outside the format are clamped to
// [INT32_MIN, INT32_MAX] raw (min() .. max()); nothing wraps.
// * add_sat / sub_sat / neg_sat: exact in 64 bits, then saturated.  No rounding is involved.
//   neg_sat(min()) == max().
// * abs_sat: |a|, exact; abs_sat(min()) == max() (the one value whose magnitude does not fit).
// * mul_sat: the 32x32 -> 64-bit product is exact and in Q32.32 (62 magnitude bits at most, one
//   guard bit); it is shifted right by 16 with rounding ((|p| + 2^15) >> 16 on the magnitude) and
//   saturated to Q16.16.
// * div_sat(a, b) (and operator/): the dividend is widened to Q32.32 (a * 2^16, |.| <= 2^47,
//   exact), divided by b's raw value in unsigned 64-bit integer arithmetic (quotient and
//   remainder), rounded (up when 2 * remainder >= |b|) and saturated.  So the result is the
//   correctly rounded, saturated quotient for every pair with b != 0; min() / -1 = +32768
//   saturates to max().  b == 0: saturates toward the sign of a (a > 0 -> max(), a < 0 -> min())
//   and 0 / 0 = 0 — a defined value, not a signal; callers that must know check b first.
// * sqrt_sat(a): the square root of a's raw value widened to Q32.32 (r * 2^16 < 2^47), by the
//   bit-by-bit (digit-by-digit, base 4) integer method on unsigned 64 bits, always exactly 32
//   steps, then rounded to nearest from the exact remainder (no ties exist for square roots).
//   The result is the correctly rounded root; sqrt_sat(max()) = 181.0193359 (raw 11863283).
//   a <= 0 gives 0 (the square root of a negative number is a domain error; 0 is its defined
//   value here, the same as for a == 0).  Never saturates.
// * hypot_sat(a, b): sqrt(a^2 + b^2) with the two squares exact in Q32.32 (each <= 2^62, the
//   sum <= 2^63 fits unsigned 64 bits), then the same 32-step integer root: the correctly rounded
//   hypotenuse with no intermediate overflow or underflow (the squares of 50 N forces, or of
//   32767 mm, are never formed in Q16.16).  Saturates only when the result itself exceeds max()
//   (|a|, |b| close to 32768).
// * ProductAccumulator: an exact sum of Q32.32 products (and of Q16.16 terms), kept as a 64-bit
//   high word (the sum's floor at 2^-16 resolution, i.e. Q48.16) plus a 16-bit low word (the
//   discarded fraction bits, 0 .. 2^16 - 1), with the carry folded in after every term.  Each
//   product contributes at most 2^46 to the high word, so the sum is EXACT for up to
//   ProductAccumulator::exact_terms = 2^16 terms (|high| < 2^62 + 2^16: 46 magnitude bits per
//   term plus 16 guard bits for the count).  Past that the high word saturates symmetrically at
//   ±(2^63 - 1) instead of wrapping.  result() rounds the exact sum once and saturates;
//   quotient(d) divides the exact Q32.32 sum by d's raw value (Q32.32 / Q16.16 = Q16.16) in
//   64-bit integers, rounds once and saturates (d == 0 as div_sat).  So (a*b + c*d) / e and
//   (a*b)/c come out correctly rounded without the Q16.16 intermediate a*b ever being formed —
//   the fused form the contact solver uses where products of compliances or of forces would
//   overflow or underflow Q16.16.
// * dot_sat<N> (and dot3_sat = dot_sat<3>): N exact Q32.32 products in a ProductAccumulator, one
//   rounding and one saturation at the end: the correctly rounded, correctly saturated value of
//   the exact sum, whatever the cancellations (N <= 2^16, checked at compile time).
// * from_int: exact for |n| <= 32767 (and -32768), saturated outside.
// * from_ratio(num, den): round(num / den * 2^16), saturated; den == 0 as div_sat.  Meant for
//   constants.
// * to_int: nearest integer (so it is exact for every integral value).
// No operation has undefined behaviour for any input (no signed overflow, no shift of a negative
// value by an out-of-range count, no division by zero).  Every loop has a compile-time bound
// (32 root steps, N terms).  No floating point is used, so results are identical on every target.
// 64-bit divisions compile to the run-time library's __aeabi_uldivmod on Cortex-M4 (no hardware
// 64-bit divide there): cost, not correctness.
#pragma once

#include <array>
#include <compare>
#include <cstddef>
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

/// |value| as unsigned 64 bits, defined for every value including INT64_MIN.
[[nodiscard]] constexpr std::uint64_t magnitude(std::int64_t value) noexcept {
    return value >= 0 ? static_cast<std::uint64_t>(value)
                      : std::uint64_t{0} - static_cast<std::uint64_t>(value);
}

/// numerator / denominator rounded to nearest (ties away from zero) and saturated to int32.
/// Any int64 numerator (INT64_MIN included), any int64 denominator.  denominator == 0 saturates
/// toward the sign of the numerator; 0 / 0 = 0.
[[nodiscard]] constexpr std::int32_t divide_round_saturate(std::int64_t numerator,
                                                           std::int64_t denominator) noexcept {
    constexpr std::uint64_t positive_limit = std::numeric_limits<std::int32_t>::max();
    constexpr std::uint64_t negative_limit = positive_limit + 1U;  // |INT32_MIN|
    if (denominator == 0) {
        return numerator > 0 ? std::numeric_limits<std::int32_t>::max()
                             : (numerator < 0 ? std::numeric_limits<std::int32_t>::min() : 0);
    }
    const bool negative = (numerator < 0) != (denominator < 0);
    const std::uint64_t n = magnitude(numerator);
    const std::uint64_t d = magnitude(denominator);
    std::uint64_t q = n / d;
    const std::uint64_t r = n % d;
    if (r >= d - r) {  // 2 r >= d without forming 2 r: round the magnitude half-up
        ++q;           // q <= 2^63 here, no wrap
    }
    if (negative) {
        return q >= negative_limit ? std::numeric_limits<std::int32_t>::min()
                                   : -static_cast<std::int32_t>(q);
    }
    return q > positive_limit ? std::numeric_limits<std::int32_t>::max()
                              : static_cast<std::int32_t>(q);
}

/// Square root of n rounded to nearest, by the bit-by-bit method: exactly 32 steps (a compile-time
/// bound, constant time), then +1 if the exact remainder n - floor^2 exceeds floor (sqrt(n) >=
/// floor + 1/2 <=> n > floor^2 + floor for integers; no ties).  Any n < 2^64; result <= 2^32.
[[nodiscard]] constexpr std::uint64_t isqrt_round(std::uint64_t n) noexcept {
    std::uint64_t remainder = n;
    std::uint64_t root = 0;
    std::uint64_t bit = std::uint64_t{1} << 62;
    for (int step = 0; step < 32; ++step) {  // bound: 32 (one result bit per step)
        if (remainder >= root + bit) {       // root < 2^32, bit <= 2^62: no wrap
            remainder -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    return remainder > root ? root + 1U : root;
}

}  // namespace detail

constexpr Q16_16 Q16_16::from_int(std::int32_t value) noexcept {
    return Q16_16{detail::saturate_to_int32(std::int64_t{value} * one_raw)};
}

constexpr Q16_16 Q16_16::from_ratio(std::int32_t numerator, std::int32_t denominator) noexcept {
    // |num| * 2^16 <= 2^47: exact.
    return Q16_16{detail::divide_round_saturate(std::int64_t{numerator} * one_raw, denominator)};
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

[[nodiscard]] constexpr Q16_16 abs_sat(Q16_16 a) noexcept {
    return a.raw() < 0 ? neg_sat(a) : a;
}

[[nodiscard]] constexpr Q16_16 mul_sat(Q16_16 a, Q16_16 b) noexcept {
    const std::int64_t product = std::int64_t{a.raw()} * b.raw();  // Q32.32, |p| <= 2^62
    return Q16_16::from_raw(
        detail::saturate_to_int32(detail::rounding_shift_right(product, Q16_16::fraction_bits)));
}

/// a / b, correctly rounded (nearest, ties away from zero) and saturated; b == 0 saturates toward
/// the sign of a, 0 / 0 = 0 (see "Scaling and overflow behaviour").
[[nodiscard]] constexpr Q16_16 div_sat(Q16_16 a, Q16_16 b) noexcept {
    return Q16_16::from_raw(
        detail::divide_round_saturate(std::int64_t{a.raw()} * Q16_16::one_raw, b.raw()));
}

/// Correctly rounded square root; 0 for a <= 0.
[[nodiscard]] constexpr Q16_16 sqrt_sat(Q16_16 a) noexcept {
    if (a.raw() <= 0) {
        return Q16_16{};
    }
    // sqrt(r / 2^16) * 2^16 = sqrt(r * 2^16); r * 2^16 < 2^47, root < 2^23.5.
    const std::uint64_t widened = static_cast<std::uint64_t>(a.raw()) << Q16_16::fraction_bits;
    return Q16_16::from_raw(static_cast<Q16_16::Raw>(detail::isqrt_round(widened)));
}

/// sqrt(a^2 + b^2), correctly rounded, with exact 64-bit squares; saturates only when the result
/// exceeds max().
[[nodiscard]] constexpr Q16_16 hypot_sat(Q16_16 a, Q16_16 b) noexcept {
    // sqrt((ra^2 + rb^2) / 2^32) * 2^16 = sqrt(ra^2 + rb^2): the raw root needs no shift.
    const std::uint64_t sum = static_cast<std::uint64_t>(std::int64_t{a.raw()} * a.raw()) +
                              static_cast<std::uint64_t>(std::int64_t{b.raw()} * b.raw());
    const std::uint64_t root = detail::isqrt_round(sum);
    constexpr std::uint64_t limit = std::numeric_limits<Q16_16::Raw>::max();
    return Q16_16::from_raw(static_cast<Q16_16::Raw>(root > limit ? limit : root));
}

/// Exact sum of Q32.32 products and Q16.16 terms (see "Scaling and overflow behaviour"): a
/// 64-bit high word (floor of the sum at 2^-16 resolution) and the 16 fraction bits below it.
/// Exact for up to exact_terms terms; rounded and saturated once, by result() or quotient().
class ProductAccumulator {
public:
    /// Terms (products or added values) that are always summed exactly.
    static constexpr std::size_t exact_terms = std::size_t{1} << 16;

    constexpr ProductAccumulator() noexcept = default;
    constexpr explicit ProductAccumulator(Q16_16 initial) noexcept { add(initial); }

    /// sum += x (exact).
    constexpr void add(Q16_16 x) noexcept {
        add_q32_32(std::int64_t{x.raw()} * Q16_16::one_raw);  // |.| <= 2^47
    }
    /// sum += a * b (exact Q32.32 product, |a b| <= 2^62).
    constexpr void add_product(Q16_16 a, Q16_16 b) noexcept {
        add_q32_32(std::int64_t{a.raw()} * b.raw());
    }
    /// The sum rounded once (nearest, ties away from zero) and saturated to Q16.16.
    [[nodiscard]] constexpr Q16_16 result() const noexcept;
    /// sum / divisor, rounded once and saturated (divisor == 0: toward the sum's sign, 0/0 = 0).
    [[nodiscard]] constexpr Q16_16 quotient(Q16_16 divisor) const noexcept;

private:
    static constexpr std::int64_t low_mask = (std::int64_t{1} << Q16_16::fraction_bits) - 1;

    constexpr void add_q32_32(std::int64_t term) noexcept {
        // term = (term >> 16) * 2^16 + (term & 0xFFFF) with the shift flooring (C++20: arithmetic).
        const std::int64_t low = low_ + (term & low_mask);  // 0 .. 2^17 - 2
        low_ = low & low_mask;
        const std::int64_t increment =
            (term >> Q16_16::fraction_bits) + (low >> Q16_16::fraction_bits);
        constexpr std::int64_t limit = std::numeric_limits<std::int64_t>::max();
        if (increment > 0 && high_ > limit - increment) {
            high_ = limit;
        } else if (increment < 0 && high_ < -limit - increment) {
            high_ = -limit;
        } else {
            high_ += increment;
        }
    }

    std::int64_t high_{0};  ///< floor(sum / 2^16), sum in Q32.32 (i.e. the sum in Q48.16, floored)
    std::int64_t low_{0};   ///< sum mod 2^16, in [0, 2^16)
};

constexpr Q16_16 ProductAccumulator::result() const noexcept {
    // sum / 2^16 = high + low / 2^16 with 0 <= low < 2^16: round up when low > 2^15; at the tie
    // low == 2^15 away from zero, i.e. up when high >= 0 (the value high + 1/2 > 0), else down.
    constexpr std::int64_t half = std::int64_t{1} << (Q16_16::fraction_bits - 1);
    constexpr std::int64_t clamp = std::int64_t{1} << 40;  // far outside int32, keeps +1 safe
    const std::int64_t high = high_ > clamp ? clamp : (high_ < -clamp ? -clamp : high_);
    const bool up = low_ > half || (low_ == half && high >= 0);
    return Q16_16::from_raw(detail::saturate_to_int32(up ? high + 1 : high));
}

constexpr Q16_16 ProductAccumulator::quotient(Q16_16 divisor) const noexcept {
    // Below |high| < 2^47 the Q32.32 sum high * 2^16 + low fits int64 exactly; at or above it
    // |sum| >= 2^63 - 2^16 > 2^31 * |divisor|, so the quotient saturates whatever the divisor.
    constexpr std::int64_t exact_limit = std::int64_t{1} << 47;
    if (high_ >= exact_limit || high_ <= -exact_limit) {
        const bool negative = (high_ < 0) != (divisor.raw() < 0);
        return negative ? Q16_16::min() : Q16_16::max();
    }
    const std::int64_t sum = high_ * Q16_16::one_raw + low_;
    return Q16_16::from_raw(detail::divide_round_saturate(sum, divisor.raw()));
}

/// a·b for N-vectors: exact products, exact accumulation, one rounding and one saturation.
template <std::size_t N>
[[nodiscard]] constexpr Q16_16 dot_sat(const std::array<Q16_16, N>& a,
                                       const std::array<Q16_16, N>& b) noexcept {
    static_assert(N <= ProductAccumulator::exact_terms,
                  "dot_sat is exact for at most ProductAccumulator::exact_terms terms");
    ProductAccumulator sum{};
    for (std::size_t i = 0; i < N; ++i) {  // bound: N (compile time)
        sum.add_product(a[i], b[i]);
    }
    return sum.result();
}

/// Saturating arithmetic operators, identical to the named functions (so generic kernels can be
/// written once for `double` and for Q16_16).
[[nodiscard]] constexpr Q16_16 operator+(Q16_16 a, Q16_16 b) noexcept {
    return add_sat(a, b);
}
[[nodiscard]] constexpr Q16_16 operator-(Q16_16 a, Q16_16 b) noexcept {
    return sub_sat(a, b);
}
[[nodiscard]] constexpr Q16_16 operator-(Q16_16 a) noexcept {
    return neg_sat(a);
}
[[nodiscard]] constexpr Q16_16 operator*(Q16_16 a, Q16_16 b) noexcept {
    return mul_sat(a, b);
}
[[nodiscard]] constexpr Q16_16 operator/(Q16_16 a, Q16_16 b) noexcept {
    return div_sat(a, b);
}

using Q16_16Vec3 = std::array<Q16_16, 3>;

/// a·b for 3-vectors: dot_sat<3> (exact products and sum, one rounding, one saturation).
[[nodiscard]] constexpr Q16_16 dot3_sat(const Q16_16Vec3& a, const Q16_16Vec3& b) noexcept {
    return dot_sat(a, b);
}

}  // namespace scopekin::fixed_point
