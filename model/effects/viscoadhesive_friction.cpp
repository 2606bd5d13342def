#include "model/effects/viscoadhesive_friction.hpp"

#include <algorithm>
#include <cmath>

namespace scopekin::model {

void ViscoadhesiveFriction::Parameters::validate(const effects::FieldName& field) const {
    // 1 s/mm would add 1 to mu at 1 mm/s: far beyond anything reported for bowel tissue.
    effects::require_in(viscous_coefficient_s_per_mm, 0.0, 1.0,
                        field("viscous_coefficient_s_per_mm"));
    effects::require_in(max_friction_increase, 0.0, 10.0, field("max_friction_increase"));
}

ViscoadhesiveFriction::ViscoadhesiveFriction(const Parameters& p) : p_(p) {
    p_.validate(effects::field_of_effect(kName));
}

std::shared_ptr<const WorldEffect> ViscoadhesiveFriction::read(const io::JsonObject& o) {
    o.allow_only({"name", "viscous_coefficient_s_per_mm", "max_friction_increase"});
    Parameters p;
    p.viscous_coefficient_s_per_mm =
        o.number_or("viscous_coefficient_s_per_mm", p.viscous_coefficient_s_per_mm);
    p.max_friction_increase = o.number_or("max_friction_increase", p.max_friction_increase);
    p.validate(effects::field_in(o));
    return std::make_shared<ViscoadhesiveFriction>(p);
}

nlohmann::json ViscoadhesiveFriction::parameters() const {
    return {{"viscous_coefficient_s_per_mm", p_.viscous_coefficient_s_per_mm},
            {"max_friction_increase", p_.max_friction_increase}};
}

double ViscoadhesiveFriction::effective_coefficient(double mu,
                                                    double sliding_speed_mm_per_s) const {
    if (p_.viscous_coefficient_s_per_mm == 0.0 || !std::isfinite(sliding_speed_mm_per_s)) return mu;
    return mu + std::min(p_.viscous_coefficient_s_per_mm * std::abs(sliding_speed_mm_per_s),
                         p_.max_friction_increase);
}

double ViscoadhesiveFriction::friction_coefficient(const ContactFrictionView& contact) const {
    return effective_coefficient(contact.mu, contact.sliding_speed_mm_per_s);
}

}  // namespace scopekin::model
