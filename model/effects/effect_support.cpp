#include "model/effects/effect_support.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/model_error.hpp"

namespace scopekin::model::effects {

FieldName field_in(const io::JsonObject& o) {
    // As JsonObject::field, on a copy of the path (the object may not outlive the namer).
    return [path = o.path()](const char* key) {
        return !path.empty() && path.back() == ':' ? path + " " + key : path + "." + key;
    };
}

FieldName field_of_effect(const std::string& effect_name) {
    return [effect_name](const char* key) { return effect_name + "." + key; };
}

void require_in(double value, double lo, double hi, const std::string& field) {
    if (!std::isfinite(value) || value < lo || value > hi)
        throw ModelError(field + ": " + number_text(value) + " must be in [" + number_text(lo) +
                         ", " + number_text(hi) + "]");
}

void require_above_at_most(double value, double lo, double hi, const std::string& field) {
    if (!std::isfinite(value) || !(value > lo) || value > hi)
        throw ModelError(field + ": " + number_text(value) + " must be in (" + number_text(lo) +
                         ", " + number_text(hi) + "]");
}

std::vector<double> node_lengths_mm(const std::vector<double>& arc) {
    const std::size_t n = arc.size();
    std::vector<double> l(n, 0.0);
    for (std::size_t k = 0; k + 1 < n; ++k) {
        const double half = 0.5 * std::abs(arc[k] - arc[k + 1]);
        l[k] += half;
        l[k + 1] += half;
    }
    return l;
}

RestColonPoint closest_rest_point(const ColonTube& colon, const Eigen::Vector3d& x,
                                  double expected_path_mm, double search_back_mm,
                                  double search_ahead_mm) {
    RestColonPoint out;
    const auto& points = colon.points();
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j + 1 < points.size(); ++j) {
        if (colon.arc_length_mm(j + 1) < expected_path_mm - search_back_mm ||
            colon.arc_length_mm(j) > expected_path_mm + search_ahead_mm)
            continue;
        const Eigen::Vector3d a = points[j].position_mm;
        const Eigen::Vector3d d = points[j + 1].position_mm - a;
        const double w = std::clamp((x - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
        const Eigen::Vector3d c = a + w * d;
        const double dist = (x - c).norm();
        if (dist < best) {
            best = dist;
            out.found = true;
            out.segment = j;
            out.weight = w;
            out.point_mm = c;
            out.distance_mm = dist;
            out.lumen_radius_mm =
                (1.0 - w) * points[j].inner_radius_mm + w * points[j + 1].inner_radius_mm;
            out.region = points[j].region;
        }
    }
    return out;
}

void for_each_node_beyond_rest_wall(const WorldEffectView& view,
                                    const std::function<bool(ColonRegion)>& in_region,
                                    const std::function<void(const NodeBeyondRestWall&)>& visit) {
    if (view.colon_at_rest == nullptr) return;
    const std::vector<double> lengths = node_lengths_mm(view.arc_from_tip_mm);
    for (std::size_t k = 0; k < view.scope_nodes_mm.size(); ++k) {
        if (k < view.scope_node_held.size() && view.scope_node_held[k]) continue;
        const double expected = view.insertion_depth_mm - view.arc_from_tip_mm[k];
        if (!(expected > 0.0)) continue;  // not past the anus
        const RestColonPoint c =
            closest_rest_point(*view.colon_at_rest, view.scope_nodes_mm[k], expected);
        if (!c.found || !in_region(c.region)) continue;
        const double excess = c.distance_mm - (c.lumen_radius_mm - view.scope_radius_mm);
        if (!(excess > 0.0) || !(c.distance_mm > 0.0)) continue;
        visit({k, excess, (view.scope_nodes_mm[k] - c.point_mm) / c.distance_mm, lengths[k],
               c.region});
    }
}

}  // namespace scopekin::model::effects
