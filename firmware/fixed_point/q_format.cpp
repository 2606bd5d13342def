// Q16.16 fixed point: everything is constexpr in q_format.hpp.  This translation unit pins, on
// every target's compiler, the bounds that the header's "Scaling and overflow behaviour" relies
// on (the hand-computed value tests are in tests/firmware/test_q_format.cpp).
#include "fixed_point/q_format.hpp"

#include <cstdint>
#include <limits>

namespace scopekin::fixed_point {

namespace {

constexpr std::int64_t int32_span = std::int64_t{1} << 31;

// Largest Q32.32 product magnitude: (-2^31)^2 = 2^62; its high word (>> 16) is 2^46, so 2^16
// terms stay below 2^62 + 2^16 and never reach the 2^63 - 1 saturation of the high word.
static_assert(int32_span * int32_span == std::int64_t{1} << 62);
static_assert((std::int64_t{1} << 46) * static_cast<std::int64_t>(ProductAccumulator::exact_terms) +
                  static_cast<std::int64_t>(ProductAccumulator::exact_terms) <
              std::numeric_limits<std::int64_t>::max());

// The root of the largest Q32.32 value fits the 32-step bit-by-bit method's 2^32 result range,
// and the widened sqrt_sat argument (raw * 2^16 < 2^47) gives a root below 2^24.
static_assert(detail::isqrt_round(std::numeric_limits<std::uint64_t>::max()) == std::uint64_t{1}
                                                                                    << 32);
static_assert(detail::isqrt_round(std::uint64_t{1} << 62) == std::uint64_t{1} << 31);

// The widened dividend of div_sat: |a| * 2^16 <= 2^47, far inside int64.
static_assert(int32_span * Q16_16::one_raw == std::int64_t{1} << 47);

}  // namespace

}  // namespace scopekin::fixed_point
