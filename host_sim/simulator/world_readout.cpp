#include "host_sim/simulator/world_readout.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace scopekin::host_sim {
namespace {

using Json = nlohmann::ordered_json;

Json vec(const Eigen::Vector3d& v) {
    return Json::array({v.x(), v.y(), v.z()});
}

Eigen::Quaterniond axis_orientation(const Eigen::Vector3d& axis, double roll_rad) {
    const Eigen::Quaterniond to_axis =
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), axis.normalized());
    return to_axis * Eigen::Quaterniond(Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()));
}

/// How far along the colon the tip may have moved between two readouts [mm]; the search
/// window. A sample every world step (<= 33 ms) at hand speeds below 1 m/s moves far less.
constexpr double kTipSearchWindow_mm = 60.0;

}  // namespace

WorldReader::WorldReader(const model::World& world) : colon_(&world.colon()) {
    const model::ColonTube& colon = *colon_;
    double start = -1, end = -1;  // S4: halfway along the sigmoid
    for (std::size_t i = 0; i < colon.point_count(); ++i) {
        if (colon.points()[i].region == model::ColonRegion::sigmoid) {
            if (start < 0) start = colon.arc_length_mm(i);
            end = colon.arc_length_mm(i);
        }
    }
    const double middle = start < 0 ? 0.5 * colon.length_mm() : 0.5 * (start + end);
    for (std::size_t i = 0; i < colon.point_count(); ++i)
        if (colon.arc_length_mm(i) <= middle) sigmoid_point_ = i;
    const double element =
        world.scope_length_mm() / static_cast<double>(world.scope_node_count() - 1);
    const long from_tip = std::lround(200.0 / element);
    node_20cm_ = static_cast<std::size_t>(
        std::max(0L, static_cast<long>(world.scope_node_count()) - 1 - from_tip));
    tip_path_mm_ = std::clamp(world.insertion_depth_mm(), 0.0, colon.length_mm());
}

double WorldReader::locate_tip(const Eigen::Vector3d& tip_mm, std::string& region) {
    double path = 0;
    std::size_t segment = 0;
    if (!colon_->closest_point_near(tip_mm, tip_path_mm_, kTipSearchWindow_mm, path, segment))
        return tip_path_mm_;
    tip_path_mm_ = path;
    region = std::string(model::region_name(colon_->points()[segment].region));
    return path;
}

WorldReadout WorldReader::read(const model::World& world) {
    WorldReadout r;
    r.time_s = world.time_s();
    r.handle_force_N = world.handle_force_N();
    r.handle_torque_Nmm = world.handle_torque_Nmm();
    r.insertion_mm = world.insertion_depth_mm();
    r.roll_rad = world.roll_rad();
    const std::size_t tip = world.scope_node_count() - 1;
    const std::array<std::size_t, 3> nodes{tip, node_20cm_, 0};
    for (std::size_t k = 0; k < nodes.size(); ++k) {
        r.em[k].position_mm = world.node_position_mm(nodes[k]);
        r.em[k].orientation = axis_orientation(world.node_axis(nodes[k]), r.roll_rad);
    }
    const std::size_t colon_nodes = colon_->points().size();
    const std::size_t next = std::min(sigmoid_point_ + 1, colon_nodes - 1);
    const std::size_t before = sigmoid_point_ == next ? next - 1 : sigmoid_point_;
    r.em[kEmSigmoid].position_mm = world.colon_position_mm(sigmoid_point_);
    const Eigen::Vector3d tangent =
        world.colon_position_mm(next) -
        (before == sigmoid_point_ ? r.em[kEmSigmoid].position_mm : world.colon_position_mm(before));
    r.em[kEmSigmoid].orientation = axis_orientation(tangent, 0.0);
    for (const model::WorldContact& c : world.contacts())
        if (c.normal_force_N > 0.0 && c.arc_from_tip_mm <= kTipStretch_mm)
            r.tip_force_N += c.force_N;
    r.tip_path_mm = locate_tip(r.em[kEmTip].position_mm, r.tip_region);
    if (r.tip_region.empty())
        r.tip_region = std::string(model::region_name(colon_->points()[0].region));
    return r;
}

WorldReadout blend(const WorldReadout& a, const WorldReadout& b, double w) {
    const auto mix = [w](double x, double y) { return x + w * (y - x); };
    WorldReadout r = w < 0.5 ? a : b;  // labels from the nearer one
    r.time_s = mix(a.time_s, b.time_s);
    r.handle_force_N = mix(a.handle_force_N, b.handle_force_N);
    r.handle_torque_Nmm = mix(a.handle_torque_Nmm, b.handle_torque_Nmm);
    r.insertion_mm = mix(a.insertion_mm, b.insertion_mm);
    r.roll_rad = mix(a.roll_rad, b.roll_rad);
    for (std::size_t k = 0; k < r.em.size(); ++k) {
        r.em[k].position_mm = a.em[k].position_mm + w * (b.em[k].position_mm - a.em[k].position_mm);
        r.em[k].orientation = a.em[k].orientation.slerp(w, b.em[k].orientation);
    }
    r.tip_force_N = a.tip_force_N + w * (b.tip_force_N - a.tip_force_N);
    r.tip_path_mm = mix(a.tip_path_mm, b.tip_path_mm);
    return r;
}

nlohmann::ordered_json WorldReader::snapshot(const model::World& world,
                                             const std::string& label) const {
    Json s;
    s["time_s"] = world.time_s();
    s["label"] = label;
    Json scope = Json::array();
    const double depth = world.insertion_depth_mm();
    for (std::size_t k = 0; k < world.scope_node_count(); ++k)
        if (world.arc_from_tip_mm(k) <= depth + 1e-9)
            scope.push_back(vec(world.node_position_mm(k)));
    s["scope_mm"] = scope;
    Json colon = Json::array();
    for (const Eigen::Vector3d& p : world.colon_positions_mm())
        colon.push_back(vec(p));
    s["colon_mm"] = colon;
    Json contacts = Json::array();
    for (const model::WorldContact& c : world.contacts())
        if (c.normal_force_N > 0.0)
            contacts.push_back({{"position_mm", vec(c.scope_point_mm)},
                                {"normal_force_N", c.normal_force_N},
                                {"force_N", vec(c.force_N)},
                                {"arc_from_tip_mm", c.arc_from_tip_mm},
                                {"region", std::string(model::region_name(c.region))}});
    s["contacts"] = contacts;
    return s;
}

nlohmann::ordered_json WorldReader::colon_json(const model::ColonTube& colon) {
    Json centerline = Json::array(), radius = Json::array(), region = Json::array();
    for (const model::ColonPoint& p : colon.points()) {
        centerline.push_back(vec(p.position_mm));
        radius.push_back(p.inner_radius_mm);
        region.push_back(std::string(model::region_name(p.region)));
    }
    return {{"centerline_mm", centerline}, {"inner_radius_mm", radius}, {"region", region}};
}

}  // namespace scopekin::host_sim
