#include "model/truth/truth_readout.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "model/model_error.hpp"
#include "model/reduction/reduced_model.hpp"

namespace scopekin::model::truth {
namespace {

/// Whether segments ab and cd of the x-y plane intersect (touching counts).
bool segments_cross_xy(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& d) {
    if (std::max(a.x(), b.x()) < std::min(c.x(), d.x()) ||
        std::max(c.x(), d.x()) < std::min(a.x(), b.x()) ||
        std::max(a.y(), b.y()) < std::min(c.y(), d.y()) ||
        std::max(c.y(), d.y()) < std::min(a.y(), b.y()))
        return false;
    const auto orient = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                           const Eigen::Vector3d& r) {
        const double v = (q.x() - p.x()) * (r.y() - p.y()) - (q.y() - p.y()) * (r.x() - p.x());
        return (v > 0) - (v < 0);
    };
    const int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a),
              o4 = orient(c, d, b);
    return o1 != o2 && o3 != o4;
}

}  // namespace

StationLayout station_layout(const World& world, std::size_t stations, double spacing_mm) {
    StationLayout layout;
    layout.stations = stations;
    layout.spacing_mm = spacing_mm;
    layout.nodes = station_nodes(world, stations, spacing_mm);
    return layout;
}

StationLayout nearest_station_layout(const World& world, std::size_t stations, double spacing_mm) {
    require_positive(spacing_mm, "truth: station spacing_mm");
    StationLayout layout;
    layout.stations = stations;
    layout.spacing_mm = spacing_mm;
    const std::size_t tip = world.scope_node_count() - 1;
    const double element_mm = world.scope_length_mm() / static_cast<double>(tip);
    for (std::size_t j = 0; j < stations; ++j) {
        const double back = std::round(spacing_mm * static_cast<double>(j) / element_mm);
        if (back > static_cast<double>(tip)) break;
        layout.nodes.push_back(tip - static_cast<std::size_t>(back));
    }
    return layout;
}

std::vector<double> displaced_arc_lengths(const std::vector<Eigen::Vector3d>& points_mm) {
    std::vector<double> arc(points_mm.size(), 0.0);
    for (std::size_t i = 1; i < points_mm.size(); ++i)
        arc[i] = arc[i - 1] + (points_mm[i] - points_mm[i - 1]).norm();
    return arc;
}

CenterlinePlace locate_on_centerline(const std::vector<Eigen::Vector3d>& points_mm,
                                     const std::vector<double>& rest_arc_mm,
                                     const std::vector<double>& displaced_arc_mm,
                                     const Eigen::Vector3d& point_mm, double from_mm,
                                     double to_mm) {
    if (points_mm.size() < 2 || rest_arc_mm.size() != points_mm.size() ||
        displaced_arc_mm.size() != points_mm.size())
        throw ModelError("locate_on_centerline: " + std::to_string(points_mm.size()) + " points, " +
                         std::to_string(rest_arc_mm.size()) + " rest arcs and " +
                         std::to_string(displaced_arc_mm.size()) +
                         " displaced arcs (at least 2 points, as many of each)");
    CenterlinePlace place;
    if (!point_mm.allFinite() || !(from_mm <= to_mm)) return place;
    double best = std::numeric_limits<double>::infinity();
    // The first segment whose end reaches from_mm (rest arcs increase).
    const auto first = std::lower_bound(rest_arc_mm.begin() + 1, rest_arc_mm.end(), from_mm);
    for (auto j = static_cast<std::size_t>(first - rest_arc_mm.begin()) - 1;
         j + 1 < points_mm.size() && rest_arc_mm[j] <= to_mm; ++j) {
        const Eigen::Vector3d d = points_mm[j + 1] - points_mm[j];
        const double len2 = d.squaredNorm();
        const double w =
            len2 > 0 ? std::clamp((point_mm - points_mm[j]).dot(d) / len2, 0.0, 1.0) : 0.0;
        const double dist = (points_mm[j] + w * d - point_mm).norm();
        if (dist < best) {
            best = dist;
            place.found = true;
            place.segment = j;
            place.weight = w;
        }
    }
    if (!place.found) return place;
    const std::size_t j = place.segment;
    const double w = place.weight;
    place.path_mm = rest_arc_mm[j] + w * (rest_arc_mm[j + 1] - rest_arc_mm[j]);
    place.displaced_path_mm =
        displaced_arc_mm[j] + w * (displaced_arc_mm[j + 1] - displaced_arc_mm[j]);
    place.distance_mm = best;
    return place;
}

bool crosses_itself_xy(const std::vector<Eigen::Vector3d>& p) {
    for (std::size_t i = 0; i + 1 < p.size(); ++i)
        for (std::size_t j = i + 2; j + 1 < p.size(); ++j)
            if (segments_cross_xy(p[i], p[i + 1], p[j], p[j + 1])) return true;
    return false;
}

TruthReader::TruthReader(const World& world, StationLayout layout,
                         const Eigen::Vector3d& gravity_mm_per_s2)
    : layout_(std::move(layout)), gravity_(gravity_mm_per_s2) {
    const ColonTube& colon = world.colon();
    if (colon.point_count() < 2) throw ModelError("truth: the colon has fewer than 2 points");
    if (layout_.stations == 0 || layout_.nodes.empty())
        throw ModelError("truth: the station layout needs at least the tip's station");
    if (layout_.nodes.size() > layout_.stations)
        throw ModelError("truth: station layout has " + std::to_string(layout_.nodes.size()) +
                         " nodes for " + std::to_string(layout_.stations) + " stations");
    for (std::size_t node : layout_.nodes)
        if (node >= world.scope_node_count())
            throw ModelError("truth: station node " + std::to_string(node) +
                             " is not on the scope");
    anus_ = colon.points()[0].position_mm;
    entry_ = (colon.points()[1].position_mm - anus_).normalized();
    rest_arc_mm_.resize(colon.point_count());
    for (std::size_t i = 0; i < colon.point_count(); ++i)
        rest_arc_mm_[i] = colon.arc_length_mm(i);
}

TruthReadout TruthReader::read(const World& world) const {
    const ColonTube& colon = world.colon();
    const auto& points = colon.points();
    TruthReadout r;
    r.time_s = world.time_s();
    r.insertion_mm = world.insertion_depth_mm();
    // The displaced centerline, point by point: World::colon_position_mm sums the colon's
    // compliance blocks of the loaded points only (O(points x loads)), where colon_positions_mm
    // multiplies the whole dense compliance matrix (O(points^2)): 7 % of a simulate run's time.
    std::vector<Eigen::Vector3d> now(points.size());
    for (std::size_t i = 0; i < now.size(); ++i)
        now[i] = world.colon_position_mm(i);
    const std::vector<double> arc = displaced_arc_lengths(now);

    // Stations: the place and frame World::probe_stations gives them (same window, same rule):
    // around the segment the contact detection tracks the node on, so the tip's coordinate is
    // continuous and follows the contact model's own idea of where the node is.
    const std::size_t k = layout_.nodes.size();  // the stations on the scope
    r.stations.resize(layout_.stations);
    StationCompliance probe;  // increasing node order (station k-1 first), frames only
    std::optional<double> deepest_beyond_wall_mm;  // over the stations placed on the centerline
    probe.stations.resize(k);
    for (std::size_t s = 0; s < k; ++s) {
        StationTruth& st = r.stations[s];
        const std::size_t node = layout_.nodes[s];
        const Eigen::Vector3d x = world.node_position_mm(node);
        const double expected = r.insertion_mm - world.arc_from_tip_mm(node);
        st.inside = (x - anus_).dot(entry_) > 1e-9 && expected > 0.0;
        if (st.inside) {
            const auto [from_mm, to_mm] = world.centerline_search_window_mm(node, kSearchBack_mm);
            const CenterlinePlace place =
                locate_on_centerline(now, rest_arc_mm_, arc, x, from_mm, to_mm);
            if (place.found) {
                const std::size_t j = place.segment;
                const Eigen::Vector3d c = now[j] + place.weight * (now[j + 1] - now[j]);
                const Eigen::Vector3d axis = (now[j + 1] - now[j]).normalized();
                st.path_mm = place.path_mm;
                const double lumen_mm = (1.0 - place.weight) * points[j].inner_radius_mm +
                                        place.weight * points[j + 1].inner_radius_mm;
                const double beyond_mm = place.distance_mm - lumen_mm;
                deepest_beyond_wall_mm =
                    std::max(deepest_beyond_wall_mm.value_or(beyond_mm), beyond_mm);
                st.displaced_path_mm = place.displaced_path_mm;
                st.region = points[j].region;
                Eigen::Vector3d n = c - x;
                n -= n.dot(axis) * axis;
                if (n.norm() < 1e-6) {
                    n = -gravity_ - (-gravity_).dot(axis) * axis;
                    if (n.norm() < 1e-9) n = axis.unitOrthogonal();
                }
                n.normalize();
                const Eigen::Vector3d t = (axis - axis.dot(n) * n).normalized();
                st.frame.col(0) = n;
                st.frame.col(1) = t;
                st.frame.col(2) = n.cross(t);
            }
        }
        probe.stations[k - 1 - s].frame = st.frame;
        probe.stations[k - 1 - s].inside = st.inside;
    }
    r.scope_beyond_wall_mm = deepest_beyond_wall_mm.value_or(0.0);
    const std::vector<Eigen::Vector3d> forces = station_forces(world, probe, k, layout_.spacing_mm);
    for (std::size_t s = 0; s < k; ++s) {
        r.stations[s].force_N = forces[s];
        const double f = forces[s].norm();
        if (f > r.max_station_force_N) {
            r.max_station_force_N = f;
            r.max_station = s;
        }
    }
    const StationTruth& tip = r.stations.front();
    r.tip_path_mm = tip.path_mm;
    r.tip_displaced_path_mm = tip.displaced_path_mm;
    r.tip_region = tip.region;

    // The largest single wall force and where it is along the colon.
    const WorldContact* largest = nullptr;
    for (const WorldContact& c : world.contacts())
        if (c.normal_force_N > 0.0 &&
            (largest == nullptr || c.force_N.norm() > r.max_wall_force_N)) {
            largest = &c;
            r.max_wall_force_N = c.force_N.norm();
        }
    if (largest != nullptr) {
        r.has_wall_force = true;
        r.max_wall_region = largest->region;
        const double expected = r.insertion_mm - largest->arc_from_tip_mm;
        const auto [from_mm, to_mm] =
            world.centerline_search_window_mm(largest->scope_node, kSearchBack_mm);
        const CenterlinePlace place =
            locate_on_centerline(now, rest_arc_mm_, arc, largest->scope_point_mm, from_mm, to_mm);
        r.max_wall_path_mm = place.found ? place.path_mm : std::max(0.0, expected);
    }

    // Loop shape: the colon point moved farthest, and whether the inserted scope crosses itself.
    for (std::size_t i = 0; i < now.size(); ++i) {
        const double moved = (now[i] - points[i].position_mm).norm();
        const ColonRegion region = points[std::min(i, points.size() - 2)].region;
        for (std::size_t g = 0; g < kColonRegionsInOrder.size(); ++g)
            if (kColonRegionsInOrder[g] == region)
                r.region_bow_mm[g] = std::max(r.region_bow_mm[g], moved);
        if (moved > r.bow_mm) {
            r.bow_mm = moved;
            r.bow_region = region;
        }
    }
    std::vector<Eigen::Vector3d> inserted;
    for (std::size_t node = 0; node < world.scope_node_count(); ++node)
        if (world.arc_from_tip_mm(node) <= r.insertion_mm + 1e-9)
            inserted.push_back(world.node_position_mm(node));
    r.scope_crosses = crosses_itself_xy(inserted);
    return r;
}

}  // namespace scopekin::model::truth
