#include "model/effects/tissue_stiffening.hpp"

#include <algorithm>
#include <cmath>

#include "model/model_error.hpp"

namespace scopekin::model {

void TissueStiffening::Parameters::validate(const effects::FieldName& field) const {
    // 1000 / N: f_ref = 1 mN, far below a scope's own weight on one node.
    effects::require_in(stiffening_per_N, 0.0, 1000.0, field("stiffening_per_N"));
}

TissueStiffening::TissueStiffening(const Parameters& p) : p_(p) {
    p_.validate(effects::field_of_effect(kName));
}

std::shared_ptr<const WorldEffect> TissueStiffening::read(const io::JsonObject& o) {
    o.allow_only({"name", "stiffening_per_N", "reference_force_N"});
    Parameters p;
    if (o.has("stiffening_per_N") && o.has("reference_force_N"))
        throw ModelError(o.field("reference_force_N") +
                         ": give either stiffening_per_N or reference_force_N (= 1 / "
                         "stiffening_per_N), not both");
    if (o.has("reference_force_N")) {
        const double f_ref = o.number("reference_force_N");
        effects::require_in(f_ref, 1e-3, 1e12, o.field("reference_force_N"));
        p.stiffening_per_N = 1.0 / f_ref;
    } else {
        p.stiffening_per_N = o.number_or("stiffening_per_N", p.stiffening_per_N);
    }
    p.validate(effects::field_in(o));
    return std::make_shared<TissueStiffening>(p);
}

nlohmann::json TissueStiffening::parameters() const {
    return {{"stiffening_per_N", p_.stiffening_per_N}};
}

double TissueStiffening::secant_compliance_mm_per_N(double c0, double f) const {
    const double x = p_.stiffening_per_N * std::max(0.0, f);
    if (p_.stiffening_per_N == 0.0 || !(x > 0.0)) return c0;
    if (x < 1e-6) return c0 * (1.0 - 0.5 * x + x * x / 3.0);  // series of ln(1 + x) / x
    return c0 * std::log1p(x) / x;
}

double TissueStiffening::indentation_mm(double c0, double f) const {
    return secant_compliance_mm_per_N(c0, f) * f;
}

double TissueStiffening::wall_compliance_mm_per_N(const ContactWallView& contact) const {
    return secant_compliance_mm_per_N(contact.base_compliance_mm_per_N,
                                      contact.previous_normal_force_N);
}

}  // namespace scopekin::model
