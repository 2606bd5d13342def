#include "model/effects/ei_scale.hpp"

namespace scopekin::model {

void EiScale::Parameters::validate(const effects::FieldName& field) const {
    effects::require_above_at_most(factor, 0.0, 10.0, field("factor"));
}

EiScale::EiScale(const Parameters& p) : p_(p) {
    p_.validate(effects::field_of_effect(kName));
}

std::shared_ptr<const WorldEffect> EiScale::read(const io::JsonObject& o) {
    o.allow_only({"name", "factor"});
    Parameters p;
    p.factor = o.number_or("factor", p.factor);
    p.validate(effects::field_in(o));
    return std::make_shared<EiScale>(p);
}

nlohmann::json EiScale::parameters() const {
    return {{"factor", p_.factor}};
}

void EiScale::adjust_scope_sections(std::vector<BeamSection>& sections,
                                    double /*scope_length_mm*/) const {
    for (BeamSection& s : sections) {
        s.bending_stiffness_y_Nmm2 *= p_.factor;
        s.bending_stiffness_z_Nmm2 *= p_.factor;
    }
}

}  // namespace scopekin::model
