#pragma once
// Shared pieces of the truth effects (model/effects/EFFECTS.md): range checks that name the
// field, the scope length each node stands for, and where a scope node is along the colon at rest.
#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "model/colon/colon_tube.hpp"
#include "model/io/strict_json.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model::effects {

/// Names a parameter in messages: "file.json: truth_effects[0].factor" when read from a file,
/// "ei_scale.factor" when constructed in code.
using FieldName = std::function<std::string(const char* key)>;
FieldName field_in(const io::JsonObject& o);
FieldName field_of_effect(const std::string& effect_name);

/// Throws ModelError("<field>: <value> must be in [lo, hi]") unless lo <= value <= hi (finite).
void require_in(double value, double lo, double hi, const std::string& field);
/// Throws unless lo < value <= hi (finite).
void require_above_at_most(double value, double lo, double hi, const std::string& field);

/// Length of scope each node carries [mm]: half of each adjacent element, from the nodes'
/// distances from the tip (node 0 = handle).
std::vector<double> node_lengths_mm(const std::vector<double>& arc_from_tip_mm);

/// The closest point of the colon's centerline at rest to a scope node.
struct RestColonPoint {
    bool found = false;
    std::size_t segment = 0;  ///< centerline segment j (points j, j + 1)
    double weight = 0;        ///< position on the segment, 0 .. 1
    Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();
    double distance_mm = 0;  ///< of the node from the centerline
    double lumen_radius_mm = 0;
    ColonRegion region = ColonRegion::rectum;  ///< the segment's region
};

/// Searches the centerline segments whose arc length overlaps [expected_path_mm - search_back_mm,
/// expected_path_mm + search_ahead_mm]: a node `arc_from_tip` from the tip of a scope inserted
/// `depth` cannot be further along the colon than depth - arc_from_tip, and the window keeps it
/// off other turns of a loop (as World::probe_stations does). Not found when the window is empty.
RestColonPoint closest_rest_point(const ColonTube& colon, const Eigen::Vector3d& node_mm,
                                  double expected_path_mm, double search_back_mm = 400.0,
                                  double search_ahead_mm = 5.0);

/// A scope node that pushes the colon's rest wall out.
struct NodeBeyondRestWall {
    std::size_t node = 0;
    double excess_mm = 0;  ///< d - (R - r) > 0: how far it pushes the wall out
    Eigen::Vector3d outward =
        Eigen::Vector3d::Zero();  ///< unit, from the rest centerline to the node
    double node_length_mm = 0;    ///< scope length the node carries
    ColonRegion region = ColonRegion::rectum;
};

/// Calls `visit` for every inserted scope node, not held by the hand, whose closest rest
/// centerline point (closest_rest_point, from its expected place depth - arc) lies in a region
/// `in_region` accepts and which is further than R - r from that centerline.
void for_each_node_beyond_rest_wall(const WorldEffectView& view,
                                    const std::function<bool(ColonRegion)>& in_region,
                                    const std::function<void(const NodeBeyondRestWall&)>& visit);

}  // namespace scopekin::model::effects
