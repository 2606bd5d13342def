#include "fixed_point/q_format.hpp"

#include <Eigen/Core>

namespace scopekin::fixed_point {

namespace {

using RawVec3 = Eigen::Matrix<std::int32_t, 3, 1>;
using WideVec3 = Eigen::Matrix<std::int64_t, 3, 1>;

RawVec3 raw_vector(const Q16_16Vec3& v) noexcept {
    return RawVec3{v[0].raw(), v[1].raw(), v[2].raw()};
}

/// a + b saturated symmetrically to ±(2^63 - 1), so the result can always be negated.
std::int64_t add_sat_symmetric(std::int64_t a, std::int64_t b) noexcept {
    constexpr std::int64_t limit = std::numeric_limits<std::int64_t>::max();
    std::int64_t sum = 0;
    if (__builtin_add_overflow(a, b, &sum)) {
        return a > 0 ? limit : -limit;
    }
    return sum < -limit ? -limit : sum;
}

}  // namespace

Q16_16 dot3_sat(const Q16_16Vec3& a, const Q16_16Vec3& b) noexcept {
    // Exact Q32.32 products, |p_i| <= 2^62.
    const WideVec3 products =
        raw_vector(a).cast<std::int64_t>().cwiseProduct(raw_vector(b).cast<std::int64_t>());
    std::int64_t accumulator = 0;
    for (Eigen::Index i = 0; i < products.size(); ++i) {  // bound: 3 (fixed-size vector)
        accumulator = add_sat_symmetric(accumulator, products[i]);
    }
    return Q16_16::from_raw(detail::saturate_to_int32(
        detail::rounding_shift_right(accumulator, Q16_16::fraction_bits)));
}

}  // namespace scopekin::fixed_point
