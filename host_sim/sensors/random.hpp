#pragma once
// Random numbers that are the same on every platform for a given seed.
//
// * SplitMix64 (Steele, Lea & Flood 2014; Vigna's splitmix64.c): seeds the generators.
// * xoshiro256** 1.0 (Blackman & Vigna 2018): the generator.
// * Normal deviates by Box–Muller.  std::normal_distribution is implementation-defined (libstdc++
//   and libc++ give different numbers), and so are std::log / std::sin / std::cos to the last bit
//   (each libm rounds differently, some use FMA), so the logarithm and the sine/cosine here are
//   computed from +, −, ×, ÷ and sqrt only — operations IEEE 754 defines exactly — in a fixed
//   order.  The sensors library is compiled with -ffp-contract=off so no compiler fuses them.
//   Accuracy: a few ulp (checked against std:: in the tests), far beyond what noise needs.
#include <array>
#include <cstdint>

namespace scopekin::sensors {

class SplitMix64 {
public:
    explicit SplitMix64(std::uint64_t state) : state_(state) {}
    std::uint64_t next();

private:
    std::uint64_t state_;
};

class Xoshiro256StarStar {
public:
    /// State = four successive SplitMix64 outputs from `seed` (the seeding the authors recommend).
    explicit Xoshiro256StarStar(std::uint64_t seed);
    /// A given state (not all zero).
    static Xoshiro256StarStar from_state(const std::array<std::uint64_t, 4>& state);

    std::uint64_t next();
    /// Uniform in [0, 1), 53 random bits.
    double uniform();
    /// Uniform in (0, 1], 53 random bits (never 0: the Box–Muller logarithm needs that).
    double uniform_positive();

private:
    Xoshiro256StarStar() = default;
    std::array<std::uint64_t, 4> s_{};
};

/// Standard normal deviates (mean 0, SD 1) by Box–Muller; the second value of each pair is kept
/// for the next call.
class NormalSampler {
public:
    double next(Xoshiro256StarStar& rng);

private:
    bool has_spare_ = false;
    double spare_ = 0;
};

/// Natural logarithm of x > 0 (finite), from IEEE-exact operations.
double portable_log(double x);
/// sin(x) and cos(x) for |x| < 1e6, from IEEE-exact operations.
void portable_sin_cos(double x, double& sine, double& cosine);

}  // namespace scopekin::sensors
