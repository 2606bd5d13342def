#include "model/patient/patient_random.hpp"

#include <cmath>

namespace scopekin::model {

double PatientRandom::unit() {
    return static_cast<double>(engine_() >> 11U) * 0x1.0p-53;
}

double PatientRandom::uniform(double lo, double hi) {
    return lo + (hi - lo) * unit();
}

double PatientRandom::log_uniform(double lo, double hi) {
    return lo * std::exp(std::log(hi / lo) * unit());
}

double PatientRandom::normal() {
    const double u1 = 1.0 - unit();  // (0, 1]: log(u1) is finite
    const double u2 = unit();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

double PatientRandom::truncated_normal(double mean, double sd, double lo, double hi) {
    for (int attempt = 0; attempt < 1000; ++attempt) {
        const double x = mean + sd * normal();
        if (x >= lo && x <= hi) return x;
    }
    return uniform(lo, hi);
}

bool PatientRandom::bernoulli(double p) {
    return unit() < p;
}

}  // namespace scopekin::model
