#include "host_sim/sensors/random.hpp"

#include <cmath>
#include <stdexcept>

namespace scopekin::sensors {

namespace {

constexpr std::uint64_t rotl(std::uint64_t x, int k) {
    return (x << k) | (x >> (64 - k));
}

constexpr double kTwoToMinus53 = 1.0 / 9007199254740992.0;  // 2^-53, exact
constexpr double kTwoPi = 6.283185307179586;                // nearest double to 2π

// ln 2 split so that e * kLn2Hi is exact for |e| < 2^11 (fdlibm's constants).
constexpr double kLn2Hi = 6.93147180369123816490e-01;
constexpr double kLn2Lo = 1.90821492927058770002e-10;
constexpr double kSqrtHalf = 0.70710678118654752440;

// π/2 split (fdlibm's pio2_1 / pio2_1t): q * kPio2Hi is exact for |q| < 2^20.
constexpr double kPio2Hi = 1.57079632673412561417e+00;
constexpr double kPio2Lo = 6.07710050650619224932e-11;
constexpr double kTwoOverPi = 6.36619772367581382433e-01;

}  // namespace

std::uint64_t SplitMix64::next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30U)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27U)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31U);
}

Xoshiro256StarStar::Xoshiro256StarStar(std::uint64_t seed) {
    SplitMix64 mix(seed);
    for (auto& word : s_)
        word = mix.next();
}

Xoshiro256StarStar Xoshiro256StarStar::from_state(const std::array<std::uint64_t, 4>& state) {
    if (state[0] == 0 && state[1] == 0 && state[2] == 0 && state[3] == 0)
        throw std::invalid_argument("xoshiro256**: the all-zero state is not allowed");
    Xoshiro256StarStar rng;
    rng.s_ = state;
    return rng;
}

std::uint64_t Xoshiro256StarStar::next() {
    const std::uint64_t result = rotl(s_[1] * 5U, 7) * 9U;
    const std::uint64_t t = s_[1] << 17U;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
}

double Xoshiro256StarStar::uniform() {
    return static_cast<double>(next() >> 11U) * kTwoToMinus53;
}

double Xoshiro256StarStar::uniform_positive() {
    return static_cast<double>((next() >> 11U) + 1U) * kTwoToMinus53;
}

double portable_log(double x) {
    if (!(x > 0) || !std::isfinite(x))
        throw std::domain_error("portable_log: argument must be finite and > 0");
    int exponent = 0;
    double m = std::frexp(x, &exponent);  // x = m * 2^exponent, m in [0.5, 1): exact
    if (m < kSqrtHalf) {
        m *= 2.0;  // exact
        --exponent;
    }
    // m in [√½, √2): log m = 2 atanh(s), s = (m − 1)/(m + 1), |s| <= 0.1716.
    const double s = (m - 1.0) / (m + 1.0);
    const double s2 = s * s;
    // 2 (s + s³/3 + s⁵/5 + ... + s²³/23); the next term is below 1e-20 relative.
    double series = 1.0 / 23.0;
    for (int k = 21; k >= 3; k -= 2)
        series = 1.0 / static_cast<double>(k) + s2 * series;
    const double log_m = 2.0 * s + 2.0 * s * s2 * series;
    const double e = static_cast<double>(exponent);
    return e * kLn2Hi + (log_m + e * kLn2Lo);
}

void portable_sin_cos(double x, double& sine, double& cosine) {
    if (!std::isfinite(x) || std::abs(x) >= 1e6)
        throw std::domain_error("portable_sin_cos: |x| must be < 1e6");
    const double q = std::round(x * kTwoOverPi);       // nearest quadrant; round() is exact
    const double r = (x - q * kPio2Hi) - q * kPio2Lo;  // |r| <= π/4 (+ a few ulp)
    const double r2 = r * r;
    // Taylor series to r^19 (sin) and r^20 (cos): the next terms are below 1e-22 for |r| <= π/4.
    double sin_series = -1.0 / 121645100408832000.0;  // -1/19!
    double cos_series = 1.0 / 2432902008176640000.0;  // 1/20!
    {
        double factorial_sin = 121645100408832000.0;   // 19!
        double factorial_cos = 2432902008176640000.0;  // 20!
        double sign = 1.0;
        for (int k = 17; k >= 1; k -= 2) {
            factorial_sin /= static_cast<double>((k + 1) * (k + 2));  // k! from (k + 2)!
            factorial_cos /= static_cast<double>((k + 2) * (k + 3));  // (k + 1)! from (k + 3)!
            sin_series = sign / factorial_sin + r2 * sin_series;
            cos_series = -sign / factorial_cos + r2 * cos_series;
            sign = -sign;
        }
    }
    const double s = r * sin_series;
    const double c = 1.0 + r2 * cos_series;
    const auto quadrant = static_cast<long long>(q);
    switch (((quadrant % 4) + 4) % 4) {
        case 0:
            sine = s;
            cosine = c;
            break;
        case 1:
            sine = c;
            cosine = -s;
            break;
        case 2:
            sine = -s;
            cosine = -c;
            break;
        default:
            sine = -c;
            cosine = s;
            break;
    }
}

double NormalSampler::next(Xoshiro256StarStar& rng) {
    if (has_spare_) {
        has_spare_ = false;
        return spare_;
    }
    const double u1 = rng.uniform_positive();  // (0, 1]: the log is finite
    const double u2 = rng.uniform();           // [0, 1)
    const double radius = std::sqrt(-2.0 * portable_log(u1));
    double sine = 0;
    double cosine = 0;
    portable_sin_cos(kTwoPi * u2, sine, cosine);
    spare_ = radius * sine;
    has_spare_ = true;
    return radius * cosine;
}

}  // namespace scopekin::sensors
