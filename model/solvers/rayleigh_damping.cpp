#include "model/solvers/rayleigh_damping.hpp"

#include <cmath>

#include "model/model_error.hpp"

namespace scopekin::model {

RayleighDamping RayleighDamping::from_hz_convention(double alpha, double beta) {
  require_non_negative(alpha, "damping.alpha");
  require_non_negative(beta, "damping.beta");
  return RayleighDamping{2.0 * M_PI * alpha, beta / (2.0 * M_PI)};
}

RayleighDamping RayleighDamping::thesis_cf_q160l() { return from_hz_convention(0.3864, 0.0164); }

double RayleighDamping::damping_ratio(double frequency_hz) const {
  const double w = 2.0 * M_PI * frequency_hz;
  return mass_coefficient_per_s / (2.0 * w) + stiffness_coefficient_s * w / 2.0;
}

}  // namespace scopekin::model
