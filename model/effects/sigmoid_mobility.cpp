#include "model/effects/sigmoid_mobility.hpp"

#include <cmath>

#include "model/model_error.hpp"

namespace scopekin::model {

void SigmoidMobility::Parameters::validate(const effects::FieldName& field) const {
    effects::require_in(amplitude_N_per_mm, 0.0, 1.0, field("amplitude_N_per_mm"));
    effects::require_above_at_most(frequency_Hz, 0.0, 5.0, field("frequency_Hz"));
    if (!direction.allFinite() || !(direction.norm() > 1e-12))
        throw ModelError(field("direction") + ": must be a finite, non-zero vector");
    require_finite(phase_rad, field("phase_rad"));
}

SigmoidMobility::SigmoidMobility(const Parameters& p) : p_(p) {
    p_.validate(effects::field_of_effect(kName));
    p_.direction.normalize();
}

std::shared_ptr<const WorldEffect> SigmoidMobility::read(const io::JsonObject& o) {
    o.allow_only({"name", "amplitude_N_per_mm", "frequency_Hz", "direction", "phase_rad"});
    Parameters p;
    p.amplitude_N_per_mm = o.number_or("amplitude_N_per_mm", p.amplitude_N_per_mm);
    p.frequency_Hz = o.number_or("frequency_Hz", p.frequency_Hz);
    p.direction = o.vector3_or("direction", p.direction);
    p.phase_rad = o.number_or("phase_rad", p.phase_rad);
    p.validate(effects::field_in(o));
    return std::make_shared<SigmoidMobility>(p);
}

nlohmann::json SigmoidMobility::parameters() const {
    return {{"amplitude_N_per_mm", p_.amplitude_N_per_mm},
            {"frequency_Hz", p_.frequency_Hz},
            {"direction", {p_.direction.x(), p_.direction.y(), p_.direction.z()}},
            {"phase_rad", p_.phase_rad}};
}

Eigen::Vector3d SigmoidMobility::load_per_length_N_per_mm(double time_s) const {
    return p_.amplitude_N_per_mm * std::sin(2.0 * M_PI * p_.frequency_Hz * time_s + p_.phase_rad) *
           p_.direction;
}

void SigmoidMobility::add_scope_loads(const WorldEffectView& view,
                                      std::vector<NodalLoad>& loads) const {
    if (p_.amplitude_N_per_mm == 0.0 || view.colon_at_rest == nullptr) return;
    const Eigen::Vector3d q = load_per_length_N_per_mm(view.time_s);
    const std::vector<double> lengths = effects::node_lengths_mm(view.arc_from_tip_mm);
    for (std::size_t k = 0; k < view.scope_nodes_mm.size(); ++k) {
        if (k < view.scope_node_held.size() && view.scope_node_held[k]) continue;
        const double expected = view.insertion_depth_mm - view.arc_from_tip_mm[k];
        if (!(expected > 0.0)) continue;
        const effects::RestColonPoint c =
            effects::closest_rest_point(*view.colon_at_rest, view.scope_nodes_mm[k], expected);
        if (!c.found || c.region != ColonRegion::sigmoid) continue;
        NodalLoad load;
        load.node = k;
        load.force_N = lengths[k] * q;
        loads.push_back(load);
    }
}

}  // namespace scopekin::model
