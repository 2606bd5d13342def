#include "model/effects/ei_profile.hpp"

#include <limits>

namespace scopekin::model {

void EiProfile::Parameters::validate(const effects::FieldName& field) const {
    effects::require_above_at_most(tip_factor, 0.0, 10.0, field("tip_factor"));
    effects::require_above_at_most(handle_factor, 0.0, 10.0, field("handle_factor"));
    effects::require_in(bending_section_length_mm, 0.0, 10000.0,
                        field("bending_section_length_mm"));
    effects::require_above_at_most(bending_section_factor, 0.0, 10.0,
                                   field("bending_section_factor"));
}

EiProfile::EiProfile(const Parameters& p) : p_(p) {
    p_.validate(effects::field_of_effect(kName));
}

std::shared_ptr<const WorldEffect> EiProfile::read(const io::JsonObject& o) {
    o.allow_only({"name", "tip_factor", "handle_factor", "bending_section_length_mm",
                  "bending_section_factor"});
    Parameters p;
    p.tip_factor = o.number_or("tip_factor", p.tip_factor);
    p.handle_factor = o.number_or("handle_factor", p.handle_factor);
    p.bending_section_length_mm =
        o.number_or("bending_section_length_mm", p.bending_section_length_mm);
    p.bending_section_factor = o.number_or("bending_section_factor", p.bending_section_factor);
    p.validate(effects::field_in(o));
    return std::make_shared<EiProfile>(p);
}

nlohmann::json EiProfile::parameters() const {
    return {{"tip_factor", p_.tip_factor},
            {"handle_factor", p_.handle_factor},
            {"bending_section_length_mm", p_.bending_section_length_mm},
            {"bending_section_factor", p_.bending_section_factor}};
}

double EiProfile::factor_at(double arc_from_tip_mm, double scope_length_mm) const {
    const double s = scope_length_mm > 0.0 ? arc_from_tip_mm / scope_length_mm : 0.0;
    double f = p_.tip_factor + (p_.handle_factor - p_.tip_factor) * s;
    if (arc_from_tip_mm < p_.bending_section_length_mm) f *= p_.bending_section_factor;
    return f;
}

void EiProfile::adjust_scope_sections(std::vector<BeamSection>& sections,
                                      double scope_length_mm) const {
    const double n = static_cast<double>(sections.size());
    for (std::size_t i = 0; i < sections.size(); ++i) {
        // Element i spans nodes i .. i + 1 (node 0 = handle): its midpoint is L (1 - (i + 0.5) / n) from the tip.
        const double mid_from_tip = scope_length_mm * (1.0 - (static_cast<double>(i) + 0.5) / n);
        const double f = factor_at(mid_from_tip, scope_length_mm);
        sections[i].bending_stiffness_y_Nmm2 *= f;
        sections[i].bending_stiffness_z_Nmm2 *= f;
    }
}

}  // namespace scopekin::model
