#include "model/effects/mesenteric_retraction.hpp"

#include <algorithm>
#include <cmath>

namespace scopekin::model {

void MesentericRetraction::Parameters::validate(const effects::FieldName& field) const {
  effects::require_in(stiffness_N_per_mm2, 0.0, 1.0, field("stiffness_N_per_mm2"));
  effects::require_in(exponent, 1.0, 4.0, field("exponent"));
  effects::require_above_at_most(reference_excess_mm, 0.0, 1000.0, field("reference_excess_mm"));
}

MesentericRetraction::MesentericRetraction(const Parameters& p) : p_(p) { p_.validate(effects::field_of_effect(kName)); }

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
  const double stretch = p_.exponent == 1.0
                             ? excess_mm
                             : p_.reference_excess_mm * std::pow(excess_mm / p_.reference_excess_mm, p_.exponent);
  return p_.stiffness_N_per_mm2 * node_length_mm * stretch;
}

void MesentericRetraction::add_scope_loads(const WorldEffectView& view, std::vector<NodalLoad>& loads) const {
  if (p_.stiffness_N_per_mm2 == 0.0 || view.colon_at_rest == nullptr) return;
  const std::vector<double> lengths = effects::node_lengths_mm(view.arc_from_tip_mm);
  for (std::size_t k = 0; k < view.scope_nodes_mm.size(); ++k) {
    if (k < view.scope_node_held.size() && view.scope_node_held[k]) continue;
    const double expected = view.insertion_depth_mm - view.arc_from_tip_mm[k];
    if (!(expected > 0.0)) continue;  // not past the anus
    const effects::RestColonPoint c = effects::closest_rest_point(*view.colon_at_rest, view.scope_nodes_mm[k], expected);
    if (!c.found || c.region != ColonRegion::sigmoid) continue;
    const double excess = c.distance_mm - (c.lumen_radius_mm - view.scope_radius_mm);
    const double f = force_N(excess, lengths[k]);
    if (!(f > 0.0) || !(c.distance_mm > 0.0)) continue;
    const Eigen::Vector3d u = (view.scope_nodes_mm[k] - c.point_mm) / c.distance_mm;
    NodalLoad load;
    load.node = k;
    load.force_N = -f * u;
    loads.push_back(load);
  }
}

}  // namespace scopekin::model
