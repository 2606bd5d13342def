#pragma once
#include <string>
// Rayleigh damping C = a M + b K (thesis Eq. 4.7, values Eq. 4.15).
//
// Units trap (model/PHYSICS.md §2.4): the thesis's a = 0.3864, b = 0.0164 satisfy
// 2 zeta f = a + b f^2 with f in Hz (check: 2*0.085*7 = 0.3864 + 0.0164*49), not the usual
// 2 zeta w = a' + b' w^2 with w in rad/s. Converting: a' = 2 pi a [1/s], b' = b / (2 pi) [s].
// The model stores a' and b' (SI-style, w in rad/s); C then has units N s/mm with M in t.
namespace scopekin::model {

struct RayleighDamping {
    double mass_coefficient_per_s = 0;   ///< a' [1/s]
    double stiffness_coefficient_s = 0;  ///< b' [s]

    /// From coefficients fitted with frequencies in Hz (the thesis's convention).
    static RayleighDamping from_hz_convention(double alpha_hz_convention,
                                              double beta_hz_convention);
    /// The thesis's Eq. (4.15): alpha = 0.3864, beta = 0.0164 (Hz convention).
    static RayleighDamping thesis_cf_q160l();
    /// Modal damping ratio of a mode with natural frequency f [Hz]: zeta = a'/(2w) + b' w/2.
    double damping_ratio(double frequency_hz) const;
};

/// Checks an implicit time step (in [0.001, 0.033] s) and damping coefficients (>= 0); errors
/// name the fields under `prefix` ("dynamic", "solver").
void validate_time_step_and_damping(double time_step_s, const RayleighDamping& damping,
                                    const std::string& prefix);

}  // namespace scopekin::model
