#include "model/solvers/rayleigh_damping.hpp"

#include <cmath>

#include "model/model_error.hpp"

namespace scopekin::model {

RayleighDamping RayleighDamping::from_hz_convention(double alpha, double beta) {
    require_non_negative(alpha, "damping.alpha");
    require_non_negative(beta, "damping.beta");
    return RayleighDamping{2.0 * M_PI * alpha, beta / (2.0 * M_PI)};
}

RayleighDamping RayleighDamping::thesis_cf_q160l() {
    return from_hz_convention(0.3864, 0.0164);
}

double RayleighDamping::damping_ratio(double frequency_hz) const {
    const double w = 2.0 * M_PI * frequency_hz;
    return mass_coefficient_per_s / (2.0 * w) + stiffness_coefficient_s * w / 2.0;
}

void validate_time_step_and_damping(double time_step_s, const RayleighDamping& damping,
                                    const std::string& prefix) {
    require_positive(time_step_s, prefix + ".time_step_s");
    if (time_step_s < 0.001 - 1e-12 || time_step_s > 0.033 + 1e-12)
        throw ModelError(prefix + ".time_step_s: " + std::to_string(time_step_s) +
                         " s is outside [0.001, 0.033] s");
    require_non_negative(damping.mass_coefficient_per_s,
                         prefix + ".damping.mass_coefficient_per_s");
    require_non_negative(damping.stiffness_coefficient_s,
                         prefix + ".damping.stiffness_coefficient_s");
}

}  // namespace scopekin::model
