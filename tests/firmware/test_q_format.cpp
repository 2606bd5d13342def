// Q16.16 fixed-point: checks against hand-computed raw values (raw = value * 65536).
// Runs as GoogleTest on x86-64 / aarch64 and with portable_check's runner on Cortex-M4.
#include <cstdint>
#include <limits>

#include "fixed_point/q_format.hpp"
#include "portable_check.hpp"

namespace {

using scopekin::fixed_point::Q16_16;
using scopekin::fixed_point::Q16_16Vec3;
using scopekin::fixed_point::add_sat;
using scopekin::fixed_point::dot3_sat;
using scopekin::fixed_point::mul_sat;
using scopekin::fixed_point::neg_sat;
using scopekin::fixed_point::sub_sat;

constexpr std::int32_t raw_max = std::numeric_limits<std::int32_t>::max();  //  2147483647
constexpr std::int32_t raw_min = std::numeric_limits<std::int32_t>::min();  // -2147483648

constexpr Q16_16 raw(std::int32_t r) { return Q16_16::from_raw(r); }

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
    SCOPEKIN_EXPECT_EQ(raw(98304).to_int(), 2);    //  1.5        ->  2
    SCOPEKIN_EXPECT_EQ(raw(-98304).to_int(), -2);  // -1.5        -> -2
    SCOPEKIN_EXPECT_EQ(raw(98303).to_int(), 1);    //  1.49998    ->  1
    SCOPEKIN_EXPECT_EQ(raw(163840).to_int(), 3);   //  2.5        ->  3
    SCOPEKIN_EXPECT_EQ(raw(-32767).to_int(), 0);   // -0.49998    ->  0
    SCOPEKIN_EXPECT_EQ(Q16_16::max().to_int(), 32768);  // 32767.99998 -> 32768
    SCOPEKIN_EXPECT_EQ(Q16_16::min().to_int(), -32768);
}

SCOPEKIN_TEST(Q16_16, MultiplicationOfExactValuesIsExact) {
    SCOPEKIN_EXPECT_EQ(mul_sat(one_and_half, two_and_quarter).raw(), 221184);        // 3.375
    SCOPEKIN_EXPECT_EQ(mul_sat(neg_sat(one_and_half), two_and_quarter).raw(), -221184);
    SCOPEKIN_EXPECT_EQ(mul_sat(half, half).raw(), 16384);                            // 0.25
    SCOPEKIN_EXPECT_EQ((Q16_16::from_int(-7) * Q16_16::from_int(6)).raw(), -2752512);  // -42
}

SCOPEKIN_TEST(Q16_16, MultiplicationRoundsHalfAwayFromZero) {
    SCOPEKIN_EXPECT_EQ(mul_sat(lsb, half).raw(), 1);         //  0.5 LSB  ->  1
    SCOPEKIN_EXPECT_EQ(mul_sat(raw(-1), half).raw(), -1);    // -0.5 LSB  -> -1
    SCOPEKIN_EXPECT_EQ(mul_sat(lsb, raw(32767)).raw(), 0);   //  0.49998 LSB -> 0
    SCOPEKIN_EXPECT_EQ(mul_sat(raw(3), half).raw(), 2);      //  1.5 LSB  ->  2
    SCOPEKIN_EXPECT_EQ(mul_sat(raw(-3), half).raw(), -2);    // -1.5 LSB  -> -2
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
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(1, 3).raw(), 21845);    //  21845.33 -> 21845
    SCOPEKIN_EXPECT_EQ(Q16_16::from_ratio(2, 3).raw(), 43691);    //  43690.67 -> 43691
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

    const Q16_16Vec3 c{one_and_half, half, raw(-16384)};                      // 1.5, 0.5, -0.25
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
