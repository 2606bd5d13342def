// The portable random numbers: the generators against their published reference outputs, the
// IEEE-only logarithm and sine/cosine against std::, and the normal deviates' statistics.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "host_sim/sensors/random.hpp"

namespace {

using scopekin::sensors::NormalSampler;
using scopekin::sensors::portable_log;
using scopekin::sensors::portable_sin_cos;
using scopekin::sensors::SplitMix64;
using scopekin::sensors::Xoshiro256StarStar;

TEST(PortableRandom, SplitMix64MatchesTheReferenceOutputs) {
    // Vigna's splitmix64.c; the values of Rosetta Code's "Pseudo-random numbers/Splitmix64".
    SplitMix64 mix(1234567);
    EXPECT_EQ(mix.next(), 6457827717110365317ULL);
    EXPECT_EQ(mix.next(), 3203168211198807973ULL);
    EXPECT_EQ(mix.next(), 9817491932198370423ULL);
    EXPECT_EQ(mix.next(), 4593380528125082431ULL);
    EXPECT_EQ(mix.next(), 16408922859458223821ULL);
    EXPECT_EQ(SplitMix64(0).next(), 0xE220A8397B1DCDAFULL);
}

TEST(PortableRandom, Xoshiro256StarStarMatchesTheReferenceOutputs) {
    // xoshiro256** 1.0 (Blackman & Vigna) from the state {1, 2, 3, 4}.
    auto rng = Xoshiro256StarStar::from_state({1, 2, 3, 4});
    for (const std::uint64_t expected :
         {11520ULL, 0ULL, 1509978240ULL, 1215971899390074240ULL, 1216172134540287360ULL,
          607988272756665600ULL, 16172922978634559625ULL, 8476171486693032832ULL,
          10595114339597558777ULL, 2904607092377533576ULL})
        EXPECT_EQ(rng.next(), expected);
    EXPECT_THROW((void)Xoshiro256StarStar::from_state({0, 0, 0, 0}), std::invalid_argument);
}

TEST(PortableRandom, UniformRanges) {
    Xoshiro256StarStar rng(42);
    double sum = 0;
    constexpr int kN = 100000;
    for (int i = 0; i < kN; ++i) {
        const double u = rng.uniform();
        ASSERT_GE(u, 0.0);
        ASSERT_LT(u, 1.0);
        const double p = rng.uniform_positive();
        ASSERT_GT(p, 0.0);
        ASSERT_LE(p, 1.0);
        sum += u;
    }
    // Mean 1/2, SD of the mean sqrt(1/12 / N): within 5 SD.
    EXPECT_NEAR(sum / kN, 0.5, 5.0 * std::sqrt(1.0 / 12.0 / kN));
}

TEST(PortableRandom, LogAgreesWithStdLogToAFewUlp) {
    Xoshiro256StarStar rng(7);
    auto check = [](double x) {
        const double expected = std::log(x);
        const double got = portable_log(x);
        const double tolerance =
            4.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(expected), 1e-300);
        ASSERT_LE(std::abs(got - expected), std::max(tolerance, 1e-300)) << x;
    };
    for (int i = 0; i < 200000; ++i)
        check(rng.uniform_positive());  // Box–Muller's domain
    for (int e = -1000; e <= 1000; e += 7)
        check(std::ldexp(1.0 + rng.uniform(), e));
    for (const double x :
         {1.0, 0.5, 2.0, 1.0 + 1e-15, 1.0 - 1e-16, std::numeric_limits<double>::min(),
          std::numeric_limits<double>::denorm_min(), 1.1102230246251565e-16})
        check(x);
    EXPECT_EQ(portable_log(1.0), 0.0);
    EXPECT_THROW((void)portable_log(0.0), std::domain_error);
    EXPECT_THROW((void)portable_log(-1.0), std::domain_error);
}

TEST(PortableRandom, SinCosAgreeWithStd) {
    Xoshiro256StarStar rng(11);
    for (int i = 0; i < 200000; ++i) {
        const double x = (rng.uniform() - 0.5) * 20.0;  // ±10 rad, beyond 2π both ways
        double s = 0, c = 0;
        portable_sin_cos(x, s, c);
        ASSERT_NEAR(s, std::sin(x), 3e-16) << x;
        ASSERT_NEAR(c, std::cos(x), 3e-16) << x;
    }
    for (int i = 0; i < 10000; ++i) {
        const double x = (rng.uniform() - 0.5) * 2e5;
        double s = 0, c = 0;
        portable_sin_cos(x, s, c);
        ASSERT_NEAR(s, std::sin(x), 1e-11) << x;
        ASSERT_NEAR(c, std::cos(x), 1e-11) << x;
    }
    double s = 1, c = 0;
    portable_sin_cos(0.0, s, c);
    EXPECT_EQ(s, 0.0);
    EXPECT_EQ(c, 1.0);
}

TEST(PortableRandom, NormalDeviatesHaveTheNormalsMomentsAndQuantiles) {
    Xoshiro256StarStar rng(2024);
    NormalSampler normal;
    constexpr int kN = 100000;
    double sum = 0, sum2 = 0, sum4 = 0;
    int within1 = 0, within2 = 0;
    for (int i = 0; i < kN; ++i) {
        const double z = normal.next(rng);
        sum += z;
        sum2 += z * z;
        sum4 += z * z * z * z;
        within1 += std::abs(z) < 1.0 ? 1 : 0;
        within2 += std::abs(z) < 2.0 ? 1 : 0;
    }
    const double n = kN;
    const double mean = sum / n;
    const double variance = sum2 / n - mean * mean;
    // 5-sigma bounds: SE(mean) = 1/√N, SE(s) ≈ 1/√(2N), SE(kurtosis) ≈ √(24/N).
    EXPECT_NEAR(mean, 0.0, 5.0 / std::sqrt(n));
    EXPECT_NEAR(std::sqrt(variance), 1.0, 5.0 / std::sqrt(2.0 * n));
    EXPECT_NEAR(sum4 / n / (variance * variance), 3.0, 5.0 * std::sqrt(24.0 / n));
    // P(|z| < 1) = 0.682689, P(|z| < 2) = 0.954500 (erf(1/√2), erf(√2)); binomial 5-sigma bounds.
    EXPECT_NEAR(within1 / n, 0.682689, 5.0 * std::sqrt(0.682689 * 0.317311 / n));
    EXPECT_NEAR(within2 / n, 0.954500, 5.0 * std::sqrt(0.9545 * 0.0455 / n));
}

TEST(PortableRandom, SameSeedSameNumbersOtherSeedOtherNumbers) {
    Xoshiro256StarStar a(99), b(99), c(100);
    NormalSampler na, nb, nc;
    bool differs = false;
    for (int i = 0; i < 1000; ++i) {
        const double x = na.next(a);
        ASSERT_EQ(x, nb.next(b));
        differs = differs || x != nc.next(c);
    }
    EXPECT_TRUE(differs);
}

}  // namespace
