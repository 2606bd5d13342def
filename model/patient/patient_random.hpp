#pragma once
// The patient family's random numbers (model/patient/README.md): std::mt19937_64, whose output
// the C++ standard fixes, turned into doubles by our own transforms (the std:: distributions
// differ between standard libraries). The same seed gives the same numbers wherever exp, log,
// sqrt and cos round alike (glibc on x86-64 and aarch64).
#include <cstdint>
#include <random>

namespace scopekin::model {

class PatientRandom {
public:
    explicit PatientRandom(std::uint64_t seed) : engine_(seed) {}
    /// Uniform on [0, 1): the top 53 bits of one 64-bit output times 2^-53.
    double unit();
    /// Uniform on [lo, hi).
    double uniform(double lo, double hi);
    /// log-uniform on [lo, hi): lo (hi / lo)^u, for factors (as likely halved as doubled).
    double log_uniform(double lo, double hi);
    /// Standard normal by Box-Muller from two unit() draws (the cosine branch only).
    double normal();
    /// Normal(mean, sd) truncated to [lo, hi] by rejection; after 1000 rejections (never for
    /// the family's distributions, each keeping > 50 % of its mass) the uniform on [lo, hi).
    double truncated_normal(double mean, double sd, double lo, double hi);
    /// true with probability p.
    bool bernoulli(double p);

private:
    std::mt19937_64 engine_;
};

}  // namespace scopekin::model
