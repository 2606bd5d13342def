#include "model/beam/beam_section.hpp"

#include <cmath>

#include "model/model_error.hpp"

namespace scopekin::model {

void BeamSection::validate(const std::string& where) const {
    require_positive(axial_stiffness_N, where + "axial_stiffness_N (EA)");
    require_positive(bending_stiffness_y_Nmm2, where + "bending_stiffness_y_Nmm2 (EI_y)");
    require_positive(bending_stiffness_z_Nmm2, where + "bending_stiffness_z_Nmm2 (EI_z)");
    require_positive(torsional_stiffness_Nmm2, where + "torsional_stiffness_Nmm2 (GJ)");
    // Shear stiffness may be +inf (Euler-Bernoulli limit) but never NaN, zero or negative.
    if (std::isnan(shear_stiffness_y_N) || !(shear_stiffness_y_N > 0.0))
        throw ModelError(where + "shear_stiffness_y_N (kappa G A): must be > 0 (or infinite)");
    if (std::isnan(shear_stiffness_z_N) || !(shear_stiffness_z_N > 0.0))
        throw ModelError(where + "shear_stiffness_z_N (kappa G A): must be > 0 (or infinite)");
    require_non_negative(mass_per_length_t_per_mm, where + "mass_per_length_t_per_mm");
    require_non_negative(rotary_inertia_y_t_mm, where + "rotary_inertia_y_t_mm");
    require_non_negative(rotary_inertia_z_t_mm, where + "rotary_inertia_z_t_mm");
    require_non_negative(polar_inertia_t_mm, where + "polar_inertia_t_mm");
}

BeamSection circular_section(double radius_mm, double bending_stiffness_Nmm2,
                             double torsional_stiffness_Nmm2, double axial_stiffness_N,
                             double shear_stiffness_N, double weight_per_length_N_per_mm) {
    require_positive(radius_mm, "radius_mm");
    require_non_negative(weight_per_length_N_per_mm, "weight_per_length_N_per_mm");
    BeamSection s;
    s.axial_stiffness_N = axial_stiffness_N;
    s.bending_stiffness_y_Nmm2 = bending_stiffness_Nmm2;
    s.bending_stiffness_z_Nmm2 = bending_stiffness_Nmm2;
    s.torsional_stiffness_Nmm2 = torsional_stiffness_Nmm2;
    s.shear_stiffness_y_N = shear_stiffness_N;
    s.shear_stiffness_z_N = shear_stiffness_N;
    s.mass_per_length_t_per_mm = weight_per_length_N_per_mm / kGravity_mm_per_s2;
    const double r2 = radius_mm * radius_mm;
    s.rotary_inertia_y_t_mm = s.mass_per_length_t_per_mm * r2 / 4.0;  // rho I = rho A r^2/4
    s.rotary_inertia_z_t_mm = s.rotary_inertia_y_t_mm;
    s.polar_inertia_t_mm = s.mass_per_length_t_per_mm * r2 / 2.0;  // rho J = rho A r^2/2
    s.validate("section: ");
    return s;
}

}  // namespace scopekin::model
