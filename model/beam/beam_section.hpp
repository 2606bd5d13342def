#pragma once
// Cross-section properties of one beam element. Units: mm, N, s; mass in tonnes (t = N s^2/mm)
// so that F = m a holds with mm/s^2.
#include <limits>
#include <string>

namespace scopekin::model {

struct BeamSection {
    double axial_stiffness_N = 0;         ///< EA [N]
    double bending_stiffness_y_Nmm2 = 0;  ///< E I_y [N mm^2], bending in the local x-z plane
    double bending_stiffness_z_Nmm2 = 0;  ///< E I_z [N mm^2], bending in the local x-y plane
    double torsional_stiffness_Nmm2 = 0;  ///< G J [N mm^2]
    /// Shear stiffness kappa G A [N] along local y / z; +infinity gives Euler-Bernoulli (phi = 0).
    double shear_stiffness_y_N = std::numeric_limits<double>::infinity();
    double shear_stiffness_z_N = std::numeric_limits<double>::infinity();
    double mass_per_length_t_per_mm = 0;  ///< rho A [t/mm]
    double rotary_inertia_y_t_mm = 0;     ///< rho I_y [t mm]
    double rotary_inertia_z_t_mm = 0;     ///< rho I_z [t mm]
    double polar_inertia_t_mm = 0;        ///< rho J [t mm]

    /// Throws ModelError naming the field (prefixed by `where`) if a value is not physical.
    void validate(const std::string& where) const;
};

/// Solid circular section of radius r [mm] with given EI, GJ, EA, shear modulus-area and
/// weight per length. mass/length = weight/g, rotary inertias from I/A = r^2/4, J/A = r^2/2.
BeamSection circular_section(double radius_mm, double bending_stiffness_Nmm2,
                             double torsional_stiffness_Nmm2, double axial_stiffness_N,
                             double shear_stiffness_N, double weight_per_length_N_per_mm);

/// Standard gravity in mm/s^2.
inline constexpr double kGravity_mm_per_s2 = 9806.65;

}  // namespace scopekin::model
