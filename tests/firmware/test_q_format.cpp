// Q16.16 fixed-point: checks against hand-computed raw values (raw = value * 65536).
// Runs as GoogleTest on x86-64 / aarch64 and with portable_check's runner on Cortex-M4.
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "fixed_point/q_format.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::abs_sat;
using scopekin::fixed_point::add_sat;
using scopekin::fixed_point::div_sat;
using scopekin::fixed_point::dot3_sat;
using scopekin::fixed_point::dot_sat;
using scopekin::fixed_point::hypot_sat;
using scopekin::fixed_point::mul_sat;
using scopekin::fixed_point::neg_sat;
using scopekin::fixed_point::ProductAccumulator;
using scopekin::fixed_point::Q16_16;
using scopekin::fixed_point::Q16_16Vec3;
using scopekin::fixed_point::sqrt_sat;
using scopekin::fixed_point::sub_sat;

constexpr std::int32_t raw_max = std::numeric_limits<std::int32_t>::max();  //  2147483647
constexpr std::int32_t raw_min = std::numeric_limits<std::int32_t>::min();  // -2147483648

constexpr Q16_16 raw(std::int32_t r) {
    return Q16_16::from_raw(r);
}

// Hand-computed constants.
constexpr Q16_16 one_and_half = raw(98304);      // 1.5   = 1.5   * 65536
constexpr Q16_16 two_and_quarter = raw(147456);  // 2.25  = 2.25  * 65536
constexpr Q16_16 half = raw(32768);              // 0.5
constexpr Q16_16 lsb = raw(1);                   // 2^-16

// The same arithmetic is usable at compile time on every target.
static_assert(mul_sat(one_and_half, two_and_quarter).raw() == 221184);  // 3.375 * 65536
static_assert(Q16_16::from_ratio(1, 3).raw() == 21845);                 // 65536/3 = 21845.33
static_assert(add_sat(Q16_16::max(), lsb) == Q16_16::max());
// Rounding near the 64-bit limit must not overflow: (2^63 - 1) / 2^16 rounds up to 2^47.
static_assert(scopekin::fixed_point::detail::rounding_shift_right(
                  std::numeric_limits<std::int64_t>::max(), 16) == (std::int64_t{1} << 47));
static_assert(div_sat(Q16_16::from_int(3), Q16_16::from_int(2)).raw() == 98304);     // 1.5
static_assert(sqrt_sat(Q16_16::from_int(4)).raw() == 131072);                        // 2
static_assert(hypot_sat(Q16_16::from_int(3), Q16_16::from_int(4)).raw() == 327680);  // 5
static_assert(dot_sat(std::array<Q16_16, 2>{half, half}, std::array<Q16_16, 2>{half, half}).raw() ==
              32768);  // 0.25 + 0.25

}  // namespace

SCOPEKIN_TEST(Q16_16, FromIntIsExactInRangeAndSaturatesOutside) {
    SCOPEKIN_EXPECT_EQ(Q16_16::from_int(1).raw(), 65536);
    SCOPEKIN_EXPECT_EQ(Q16_16::from_int(-3).raw(), -196608);
    SCOPEKIN_EXPECT_EQ(Q16_16::from_int(32767).raw(), 2147418112);  // 32767 * 65536
    SCOPEKIN_EXPECT_EQ(Q16_16::from_int(-32768).raw(), raw_min);    // exactly representable
    SCOPEKIN_EXPECT_EQ(Q16_16::from_int(32768).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(Q16_16::from_int(-32769).raw(), raw_min);
}

SCOPEKIN_TEST(Q16_16, ToIntRoundsToNearestTiesAwayFromZero) {
    SCOPEKIN_EXPECT_EQ(raw(98304).to_int(), 2);         //  1.5        ->  2
    SCOPEKIN_EXPECT_EQ(raw(-98304).to_int(), -2);       // -1.5        -> -2
    SCOPEKIN_EXPECT_EQ(raw(98303).to_int(), 1);         //  1.49998    ->  1
    SCOPEKIN_EXPECT_EQ(raw(163840).to_int(), 3);        //  2.5        ->  3
    SCOPEKIN_EXPECT_EQ(raw(-32767).to_int(), 0);        // -0.49998    ->  0
    SCOPEKIN_EXPECT_EQ(Q16_16::max().to_int(), 32768);  // 32767.99998 -> 32768
    SCOPEKIN_EXPECT_EQ(Q16_16::min().to_int(), -32768);
}

SCOPEKIN_TEST(Q16_16, MultiplicationOfExactValuesIsExact) {
    SCOPEKIN_EXPECT_EQ(mul_sat(one_and_half, two_and_quarter).raw(), 221184);  // 3.375
    SCOPEKIN_EXPECT_EQ(mul_sat(neg_sat(one_and_half), two_and_quarter).raw(), -221184);
    SCOPEKIN_EXPECT_EQ(mul_sat(half, half).raw(), 16384);                              // 0.25
    SCOPEKIN_EXPECT_EQ((Q16_16::from_int(-7) * Q16_16::from_int(6)).raw(), -2752512);  // -42
}

SCOPEKIN_TEST(Q16_16, MultiplicationRoundsHalfAwayFromZero) {
    SCOPEKIN_EXPECT_EQ(mul_sat(lsb, half).raw(), 1);           //  0.5 LSB  ->  1
    SCOPEKIN_EXPECT_EQ(mul_sat(raw(-1), half).raw(), -1);      // -0.5 LSB  -> -1
    SCOPEKIN_EXPECT_EQ(mul_sat(lsb, raw(32767)).raw(), 0);     //  0.49998 LSB -> 0
    SCOPEKIN_EXPECT_EQ(mul_sat(raw(3), half).raw(), 2);        //  1.5 LSB  ->  2
    SCOPEKIN_EXPECT_EQ(mul_sat(raw(-3), half).raw(), -2);      // -1.5 LSB  -> -2
    SCOPEKIN_EXPECT_EQ(mul_sat(raw(5), raw(16384)).raw(), 1);  // 5 * 0.25 = 1.25 LSB -> 1
}

SCOPEKIN_TEST(Q16_16, MultiplicationSaturatesAtInt32Limits) {
    const Q16_16 two_hundred = Q16_16::from_int(200);  // 200^2 = 40000 > 32767.99998
    SCOPEKIN_EXPECT_EQ(mul_sat(two_hundred, two_hundred).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(mul_sat(neg_sat(two_hundred), two_hundred).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ(mul_sat(Q16_16::min(), Q16_16::min()).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(mul_sat(Q16_16::min(), Q16_16::from_int(-1)).raw(), raw_max);  // +32768
    SCOPEKIN_EXPECT_EQ(mul_sat(Q16_16::min(), Q16_16::from_int(1)).raw(), raw_min);
}

SCOPEKIN_TEST(Q16_16, AdditionAndSubtractionSaturate) {
    SCOPEKIN_EXPECT_EQ(add_sat(one_and_half, two_and_quarter).raw(), 245760);  // 3.75
    SCOPEKIN_EXPECT_EQ(sub_sat(one_and_half, two_and_quarter).raw(), -49152);  // -0.75
    SCOPEKIN_EXPECT_EQ(add_sat(Q16_16::max(), lsb).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(sub_sat(Q16_16::min(), lsb).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ(sub_sat(Q16_16::max(), Q16_16::min()).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(add_sat(Q16_16::max(), Q16_16::min()).raw(), -1);
    SCOPEKIN_EXPECT_EQ(neg_sat(Q16_16::min()).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ((-Q16_16::max()).raw(), -2147483647);
}

SCOPEKIN_TEST(Q16_16, FromRatioRoundsOneThird) {
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(1, 3).raw(), 21845);  //  21845.33 -> 21845
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(2, 3).raw(), 43691);  //  43690.67 -> 43691
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(-1, 3).raw(), -21845);
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(1, -3).raw(), -21845);
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(-2, -3).raw(), 43691);
    // One third times three is one LSB short of one: 21845 * 3 = 65535.
    SCOPEKIN_EXPECT_EQ(mul_sat(Q16_16::from_ratio(1, 3), Q16_16::from_int(3)).raw(), 65535);
}

SCOPEKIN_TEST(Q16_16, FromRatioTiesAndLimits) {
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(1, 2).raw(), 32768);
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(1, 131072).raw(), 1);    //  2^-17 = half LSB ->  1
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(-1, 131072).raw(), -1);  // -2^-17            -> -1
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(1, 131073).raw(), 0);    // just below half LSB
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(40000, 1).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(raw_min, 1).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(1, 0).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(-1, 0).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(0, 0).raw(), 0);
}

SCOPEKIN_TEST(Q16_16, Dot3IsExactForExactInputs) {
    const Q16_16Vec3 a{Q16_16::from_int(1), Q16_16::from_int(2), Q16_16::from_int(3)};
    const Q16_16Vec3 b{Q16_16::from_int(4), Q16_16::from_int(-5), Q16_16::from_int(6)};
    SCOPEKIN_EXPECT_EQ(dot3_sat(a, b).raw(), 786432);  // 4 - 10 + 18 = 12

    const Q16_16Vec3 c{one_and_half, half, raw(-16384)};  // 1.5, 0.5, -0.25
    const Q16_16Vec3 d{two_and_quarter, Q16_16::from_int(4), Q16_16::from_int(8)};
    SCOPEKIN_EXPECT_EQ(dot3_sat(c, d).raw(), 221184);  // 3.375 + 2 - 2 = 3.375
}

SCOPEKIN_TEST(Q16_16, Dot3RoundsOnceNotPerTerm) {
    // Each product is half an LSB; the exact sum is 1.5 LSB -> 2.  Rounding every product
    // separately (mul_sat) would give 1 + 1 + 1 = 3.
    const Q16_16Vec3 halves{half, half, half};
    const Q16_16Vec3 lsbs{lsb, lsb, lsb};
    SCOPEKIN_EXPECT_EQ(dot3_sat(halves, lsbs).raw(), 2);
}

SCOPEKIN_TEST(Q16_16, Dot3SaturatesAndCancelsCorrectly) {
    const Q16_16 mn = Q16_16::min();
    const Q16_16 mx = Q16_16::max();
    const Q16_16 zero{};
    // 3 * 2^62 in Q32.32: beyond the accumulator and the format -> max.
    SCOPEKIN_EXPECT_EQ(dot3_sat(Q16_16Vec3{mn, mn, mn}, Q16_16Vec3{mn, mn, mn}).raw(), raw_max);
    // 2^62 + 2^62 saturates the accumulator, then + (-2^62 + 2^31): exact sum 2^62 + 2^31 -> max.
    SCOPEKIN_EXPECT_EQ(dot3_sat(Q16_16Vec3{mn, mn, mn}, Q16_16Vec3{mn, mn, mx}).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(dot3_sat(Q16_16Vec3{mn, mn, mn}, Q16_16Vec3{mx, mx, mx}).raw(), raw_min);
    // 2^62 + (-2^62 + 2^31) = 2^31 in Q32.32 = 0.5 exactly: large terms cancel without saturating.
    SCOPEKIN_EXPECT_EQ(dot3_sat(Q16_16Vec3{mn, mx, zero}, Q16_16Vec3{mn, mn, zero}).raw(), 32768);
}

// ------------------------------------------------------------------------------------------------
// Division: raw = round(a * 65536 / b), nearest, ties away from zero, saturated.
// ------------------------------------------------------------------------------------------------

SCOPEKIN_TEST(Q16_16, DivisionOfExactValuesIsExact) {
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(3), Q16_16::from_int(2)).raw(), 98304);     // 1.5
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(-9), Q16_16::from_int(4)).raw(), -147456);  // -2.25
    SCOPEKIN_EXPECT_EQ(div_sat(one_and_half, half).raw(), 196608);                          // 3
    SCOPEKIN_EXPECT_EQ((Q16_16::from_int(-42) / Q16_16::from_int(-6)).raw(), 458752);       // 7
    SCOPEKIN_EXPECT_EQ(div_sat(lsb, lsb).raw(), 65536);                                     // 1
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::max(), Q16_16::from_int(1)).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::min(), Q16_16::from_int(1)).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::max(), Q16_16::from_int(-1)).raw(), -2147483647);
}

SCOPEKIN_TEST(Q16_16, DivisionRoundsToNearest) {
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(1), Q16_16::from_int(3)).raw(), 21845);  // .33
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(2), Q16_16::from_int(3)).raw(), 43691);  // .67
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(-2), Q16_16::from_int(3)).raw(), -43691);
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(2), Q16_16::from_int(-3)).raw(), -43691);
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(-2), Q16_16::from_int(-3)).raw(), 43691);
    // 1000 / 7 = 142.857142...: 65536000 / 7 = 9362285.71 -> 9362286.
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(1000), Q16_16::from_int(7)).raw(), 9362286);
    // Tiny divisor: (100 LSB) / (3 LSB) = 33.333: 2184533.33 -> 2184533.
    SCOPEKIN_EXPECT_EQ(div_sat(raw(100), raw(3)).raw(), 2184533);
    SCOPEKIN_EXPECT_EQ(div_sat(lsb, Q16_16::from_int(3)).raw(), 0);     // 0.33 LSB -> 0
    SCOPEKIN_EXPECT_EQ(div_sat(raw(7), Q16_16::from_int(4)).raw(), 2);  // 1.75 LSB -> 2
    SCOPEKIN_EXPECT_EQ(div_sat(raw(5), Q16_16::from_int(4)).raw(), 1);  // 1.25 LSB -> 1
}

SCOPEKIN_TEST(Q16_16, DivisionTiesRoundAwayFromZero) {
    SCOPEKIN_EXPECT_EQ(div_sat(lsb, Q16_16::from_int(2)).raw(), 1);       //  0.5 LSB ->  1
    SCOPEKIN_EXPECT_EQ(div_sat(raw(-1), Q16_16::from_int(2)).raw(), -1);  // -0.5 LSB -> -1
    SCOPEKIN_EXPECT_EQ(div_sat(lsb, Q16_16::from_int(-2)).raw(), -1);     // -0.5 LSB -> -1
    SCOPEKIN_EXPECT_EQ(div_sat(raw(3), Q16_16::from_int(2)).raw(), 2);    //  1.5 LSB ->  2
    SCOPEKIN_EXPECT_EQ(div_sat(raw(-3), Q16_16::from_int(2)).raw(), -2);  // -1.5 LSB -> -2
    SCOPEKIN_EXPECT_EQ(div_sat(raw(5), Q16_16::from_int(2)).raw(), 3);    //  2.5 LSB ->  3
}

SCOPEKIN_TEST(Q16_16, DivisionSaturatesAndHandlesZeroDivisor) {
    // min() / -1 = +32768, one LSB beyond max().
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::min(), Q16_16::from_int(-1)).raw(), raw_max);
    // -32768 / -0.99998474 = 32768.5: max().
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::min(), raw(-65535)).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(20000), half).raw(), raw_max);   //  40000
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(-20000), half).raw(), raw_min);  // -40000
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(1), lsb).raw(), raw_max);        //  65536
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::max(), raw(-1)).raw(), raw_min);
    // b == 0: toward the sign of a; 0 / 0 = 0.
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(5), Q16_16{}).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(div_sat(lsb, Q16_16{}).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::from_int(-5), Q16_16{}).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16::min(), Q16_16{}).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ(div_sat(Q16_16{}, Q16_16{}).raw(), 0);
    SCOPEKIN_EXPECT_EQ((Q16_16{} / Q16_16::from_int(-3)).raw(), 0);
}

SCOPEKIN_TEST(Q16_16, OperatorsSaturateAtBothEnds) {
    const Q16_16 big = Q16_16::from_int(30000);
    SCOPEKIN_EXPECT_EQ((big + big).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ((-big - big).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ((big * big).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ((-big * big).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ((big / half).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ((-big / half).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ((-Q16_16::min()).raw(), raw_max);
}

// ------------------------------------------------------------------------------------------------
// abs, square root, hypot.
// ------------------------------------------------------------------------------------------------

SCOPEKIN_TEST(Q16_16, AbsSaturatesOnlyAtMin) {
    SCOPEKIN_EXPECT_EQ(abs_sat(raw(-98304)).raw(), 98304);
    SCOPEKIN_EXPECT_EQ(abs_sat(raw(98304)).raw(), 98304);
    SCOPEKIN_EXPECT_EQ(abs_sat(Q16_16{}).raw(), 0);
    SCOPEKIN_EXPECT_EQ(abs_sat(Q16_16::max()).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(abs_sat(Q16_16::min()).raw(), raw_max);  // +32768 does not fit
}

SCOPEKIN_TEST(Q16_16, SquareRootIsCorrectlyRounded) {
    SCOPEKIN_EXPECT_EQ(sqrt_sat(Q16_16::from_int(4)).raw(), 131072);      // 2
    SCOPEKIN_EXPECT_EQ(sqrt_sat(Q16_16::from_int(1)).raw(), 65536);       // 1
    SCOPEKIN_EXPECT_EQ(sqrt_sat(raw(16384)).raw(), 32768);                // sqrt(0.25) = 0.5
    SCOPEKIN_EXPECT_EQ(sqrt_sat(Q16_16::from_int(2500)).raw(), 3276800);  // 50
    // sqrt(2) * 65536 = 92681.900 -> 92682 (rounds up).
    SCOPEKIN_EXPECT_EQ(sqrt_sat(Q16_16::from_int(2)).raw(), 92682);
    // sqrt(2^-16) = 2^-8: raw 256.  sqrt(2 LSB) = 362.039 raw -> 362.
    SCOPEKIN_EXPECT_EQ(sqrt_sat(lsb).raw(), 256);
    SCOPEKIN_EXPECT_EQ(sqrt_sat(raw(2)).raw(), 362);
    // raw 65535 (1 - 2^-16): sqrt(65535 * 65536) = sqrt(65535.5^2 - 0.25) = 65535.4999981:
    // just below the half, so 65535 (a root rounded from a truncated value would risk 65536).
    SCOPEKIN_EXPECT_EQ(sqrt_sat(raw(65535)).raw(), 65535);
    // sqrt(max()) = sqrt(32767.9999847) = 181.0193360: floor(sqrt(2147483647 * 65536)) =
    // 11863283, remainder 4751703 < 11863283 -> 11863283.
    SCOPEKIN_EXPECT_EQ(sqrt_sat(Q16_16::max()).raw(), 11863283);
}

SCOPEKIN_TEST(Q16_16, SquareRootOfNonPositiveIsZero) {
    SCOPEKIN_EXPECT_EQ(sqrt_sat(Q16_16{}).raw(), 0);
    SCOPEKIN_EXPECT_EQ(sqrt_sat(raw(-1)).raw(), 0);
    SCOPEKIN_EXPECT_EQ(sqrt_sat(Q16_16::min()).raw(), 0);
}

SCOPEKIN_TEST(Q16_16, HypotHasNoIntermediateOverflow) {
    SCOPEKIN_EXPECT_EQ(hypot_sat(Q16_16::from_int(3), Q16_16::from_int(4)).raw(), 327680);    // 5
    SCOPEKIN_EXPECT_EQ(hypot_sat(Q16_16::from_int(-3), Q16_16::from_int(-4)).raw(), 327680);  // 5
    // 150^2 + 200^2 = 62500 (both squares beyond Q16.16): 250 = 16384000 raw.
    SCOPEKIN_EXPECT_EQ(hypot_sat(Q16_16::from_int(150), Q16_16::from_int(200)).raw(), 16384000);
    SCOPEKIN_EXPECT_EQ(hypot_sat(Q16_16::from_int(-200), Q16_16{}).raw(), 13107200);  // 200
    // Tiny: sqrt(2) LSB = 1.414 LSB -> 1; sqrt(5) LSB = 2.236 -> 2; (3, 4) LSB -> 5 LSB.
    SCOPEKIN_EXPECT_EQ(hypot_sat(lsb, lsb).raw(), 1);
    SCOPEKIN_EXPECT_EQ(hypot_sat(raw(1), raw(-2)).raw(), 2);
    SCOPEKIN_EXPECT_EQ(hypot_sat(raw(3), raw(4)).raw(), 5);
    // sqrt(2) * 30000 = 42426 > 32767.99998: saturates; so does |min()| = 32768.
    SCOPEKIN_EXPECT_EQ(hypot_sat(Q16_16::from_int(30000), Q16_16::from_int(30000)).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(hypot_sat(Q16_16::min(), Q16_16{}).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(hypot_sat(Q16_16::min(), Q16_16::min()).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(hypot_sat(Q16_16::max(), Q16_16{}).raw(), raw_max);
}

// ------------------------------------------------------------------------------------------------
// The exact product accumulator and dot_sat<N>.
// ------------------------------------------------------------------------------------------------

SCOPEKIN_TEST(Q16_16, AccumulatorQuotientRoundsOnce) {
    // (200 * 200) / 400 = 100: 200^2 = 40000 alone would saturate Q16.16.
    ProductAccumulator a{};
    a.add_product(Q16_16::from_int(200), Q16_16::from_int(200));
    SCOPEKIN_EXPECT_EQ(a.quotient(Q16_16::from_int(400)).raw(), 6553600);
    SCOPEKIN_EXPECT_EQ(a.result().raw(), raw_max);
    // (1000 * 1000 - 999 * 1001) / 1 = 1000000 - 999999 = 1: exact cancellation.
    ProductAccumulator b{};
    b.add_product(Q16_16::from_int(1000), Q16_16::from_int(1000));
    b.add_product(Q16_16::from_int(-999), Q16_16::from_int(1001));
    SCOPEKIN_EXPECT_EQ(b.quotient(Q16_16::from_int(1)).raw(), 65536);
    SCOPEKIN_EXPECT_EQ(b.result().raw(), 65536);
    // 0.01 * 0.01 / 0.01 in raw terms: 655 * 655 / 655 LSB -> 655 (the product alone is 6.5 LSB).
    ProductAccumulator c{};
    c.add_product(raw(655), raw(655));
    SCOPEKIN_EXPECT_EQ(c.quotient(raw(655)).raw(), 655);
    // Started from a value: 2.5 + 1.5 * 2.25 = 5.875 -> raw 385024; / 2 -> 2.9375 = 192512.
    ProductAccumulator d{Q16_16::from_ratio(5, 2)};
    d.add_product(one_and_half, two_and_quarter);
    SCOPEKIN_EXPECT_EQ(d.result().raw(), 385024);
    SCOPEKIN_EXPECT_EQ(d.quotient(Q16_16::from_int(2)).raw(), 192512);
}

SCOPEKIN_TEST(Q16_16, AccumulatorTiesAndZeroDivisor) {
    // One LSB / 2 = 0.5 LSB -> 1; -1 LSB / 2 -> -1 (ties away from zero).
    SCOPEKIN_EXPECT_EQ(ProductAccumulator{lsb}.quotient(Q16_16::from_int(2)).raw(), 1);
    SCOPEKIN_EXPECT_EQ(ProductAccumulator{raw(-1)}.quotient(Q16_16::from_int(2)).raw(), -1);
    // result() of half an LSB (0.5 * 1 LSB) and of minus half an LSB.
    ProductAccumulator plus{};
    plus.add_product(half, lsb);
    SCOPEKIN_EXPECT_EQ(plus.result().raw(), 1);
    ProductAccumulator minus{};
    minus.add_product(-half, lsb);
    SCOPEKIN_EXPECT_EQ(minus.result().raw(), -1);
    // -1.5 LSB -> -2, and half + (-half) = 0 exactly.
    ProductAccumulator minus_three_halves{raw(-1)};
    minus_three_halves.add_product(-half, lsb);
    SCOPEKIN_EXPECT_EQ(minus_three_halves.result().raw(), -2);
    minus.add_product(half, lsb);
    SCOPEKIN_EXPECT_EQ(minus.result().raw(), 0);
    // Division by zero: toward the sum's sign, 0 / 0 = 0.
    SCOPEKIN_EXPECT_EQ(ProductAccumulator{lsb}.quotient(Q16_16{}).raw(), raw_max);
    SCOPEKIN_EXPECT_EQ(ProductAccumulator{raw(-1)}.quotient(Q16_16{}).raw(), raw_min);
    SCOPEKIN_EXPECT_EQ(ProductAccumulator{}.quotient(Q16_16{}).raw(), 0);
    // A sum far beyond Q16.16 divided by a small number: saturates with the right sign.
    ProductAccumulator huge{};
    huge.add_product(Q16_16::min(), Q16_16::min());  // 2^62 in Q32.32 (value 2^30)
    SCOPEKIN_EXPECT_EQ(huge.quotient(raw(-1)).raw(), raw_min);
    // 2^62 / (2^31 - 1) = 2^31 + 1.0000000005: one past the largest raw value.
    SCOPEKIN_EXPECT_EQ(huge.quotient(Q16_16::max()).raw(), raw_max);
    // 2^62 / 2^31 raw with a negative divisor: exactly -2^31 = min(), no saturation needed.
    SCOPEKIN_EXPECT_EQ(huge.quotient(Q16_16::min()).raw(), raw_min);
}

SCOPEKIN_TEST(Q16_16, DotOfManyTermsIsExactThroughLargeCancellations) {
    const Q16_16 mn = Q16_16::min();
    const Q16_16 mx = Q16_16::max();
    // 4 * 2^62 + 4 * (-2^62 + 2^31) = 2^33 in Q32.32 = 2.0: partial sums reach 2^64 (a single
    // saturating int64 accumulator would end at max()).
    const std::array<Q16_16, 8> a{mn, mn, mn, mn, mn, mn, mn, mn};
    const std::array<Q16_16, 8> b{mn, mn, mn, mn, mx, mx, mx, mx};
    SCOPEKIN_EXPECT_EQ(dot_sat(a, b).raw(), 131072);
    // The same terms, all positive: 8 * 2^62 -> max(); all negative -> min().
    SCOPEKIN_EXPECT_EQ(dot_sat(a, a).raw(), raw_max);
    const std::array<Q16_16, 8> c{mx, mx, mx, mx, mx, mx, mx, mx};
    SCOPEKIN_EXPECT_EQ(dot_sat(a, c).raw(), raw_min);
    // Twelve half-LSB products: 6 LSB exactly (per-term rounding would give 12).
    std::array<Q16_16, 12> halves{};
    std::array<Q16_16, 12> lsbs{};
    for (std::size_t i = 0; i < halves.size(); ++i) {
        halves[i] = half;
        lsbs[i] = lsb;
    }
    SCOPEKIN_EXPECT_EQ(dot_sat(halves, lsbs).raw(), 6);
    // dot3_sat is dot_sat<3>.
    SCOPEKIN_EXPECT_EQ(dot3_sat(Q16_16Vec3{half, half, half}, Q16_16Vec3{lsb, lsb, lsb}).raw(), 2);
}
