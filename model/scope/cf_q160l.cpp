#include "model/scope/cf_q160l.hpp"

#include <cmath>

namespace scopekin::model::cf_q160l {

BeamSection section(double bending_stiffness_Nmm2, double weight_per_length_N_per_mm) {
    const double r = kRadius_mm;
    const double area = M_PI * r * r;
    const double second_moment = M_PI * r * r * r * r / 4.0;
    const double polar_moment = 2.0 * second_moment;
    const double young = bending_stiffness_Nmm2 / second_moment;  // App. F: E = EI / I
    const double shear_modulus = kTorsionalStiffness_Nmm2 / polar_moment;
    return circular_section(r, bending_stiffness_Nmm2, kTorsionalStiffness_Nmm2, young * area,
                            kShearCorrection * shear_modulus * area, weight_per_length_N_per_mm);
}

RayleighDamping damping() {
    return RayleighDamping::thesis_cf_q160l();
}

}  // namespace scopekin::model::cf_q160l
