#include "model/effects/mesenteric_retraction.hpp"

#include <algorithm>
#include <cmath>

namespace scopekin::model {

void MesentericRetraction::Parameters::validate(const effects::FieldName& field) const {
    effects::require_in(stiffness_N_per_mm2, 0.0, 1.0, field("stiffness_N_per_mm2"));
    effects::require_in(exponent, 1.0, 4.0, field("exponent"));
    effects::require_above_at_most(reference_excess_mm, 0.0, 1000.0, field("reference_excess_mm"));
}

MesentericRetraction::MesentericRetraction(const Parameters& p) : p_(p) {
    p_.validate(effects::field_of_effect(kName));
}

std::shared_ptr<const WorldEffect> MesentericRetraction::read(const io::JsonObject& o) {
    o.allow_only({"name", "stiffness_N_per_mm2", "exponent", "reference_excess_mm"});
    Parameters p;
    p.stiffness_N_per_mm2 = o.number_or("stiffness_N_per_mm2", p.stiffness_N_per_mm2);
    p.exponent = o.number_or("exponent", p.exponent);
    p.reference_excess_mm = o.number_or("reference_excess_mm", p.reference_excess_mm);
    p.validate(effects::field_in(o));
    return std::make_shared<MesentericRetraction>(p);
}

nlohmann::json MesentericRetraction::parameters() const {
    return {{"stiffness_N_per_mm2", p_.stiffness_N_per_mm2},
            {"exponent", p_.exponent},
            {"reference_excess_mm", p_.reference_excess_mm}};
}

double MesentericRetraction::force_N(double excess_mm, double node_length_mm) const {
    if (!(excess_mm > 0.0)) return 0.0;
    const double stretch =
        p_.exponent == 1.0
            ? excess_mm
            : p_.reference_excess_mm * std::pow(excess_mm / p_.reference_excess_mm, p_.exponent);
    return p_.stiffness_N_per_mm2 * node_length_mm * stretch;
}

void MesentericRetraction::add_scope_loads(const WorldEffectView& view,
                                           std::vector<NodalLoad>& loads) const {
    if (p_.stiffness_N_per_mm2 == 0.0) return;
    effects::for_each_node_beyond_rest_wall(
        view, [](ColonRegion r) { return r == ColonRegion::sigmoid; },
        [&](const effects::NodeBeyondRestWall& n) {
            const double f = force_N(n.excess_mm, n.node_length_mm);
            if (f > 0.0) loads.push_back({n.node, -f * n.outward, Eigen::Vector3d::Zero()});
        });
}

}  // namespace scopekin::model
