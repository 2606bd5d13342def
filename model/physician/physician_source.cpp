#include "model/physician/physician_source.hpp"

#include <algorithm>

#include "model/model_error.hpp"
#include "model/truth/truth_readout.hpp"

namespace scopekin::model {

WorldObserver::WorldObserver(const World& world) {
    const ColonTube& colon = world.colon();
    rest_arc_mm_.reserve(colon.point_count());
    for (std::size_t i = 0; i < colon.point_count(); ++i)
        rest_arc_mm_.push_back(colon.arc_length_mm(i));
}

PhysicianObservation WorldObserver::observe(const World& world) {
    PhysicianObservation o;
    o.time_s = world.time_s();
    o.insertion_mm = world.insertion_depth_mm();
    o.handle_force_N = world.handle_force_N();
    const ColonTube& colon = world.colon();
    o.cecum_path_mm = colon.length_mm();
    double window_mm = kFirstTrackWindow_mm;
    if (tip_path_mm_ < 0)
        tip_path_mm_ = std::clamp(o.insertion_mm, 0.0, colon.length_mm());
    else
        window_mm = std::max(kMinTrackWindow_mm, kMaxTipSpeed_mm_per_s * (o.time_s - last_time_s_));
    last_time_s_ = o.time_s;
    // Only the colon points around the tip's last place are displaced and searched (the
    // displacement of every point costs about as much as a sixth of a world step).
    const double from_mm = tip_path_mm_ - window_mm, to_mm = tip_path_mm_ + window_mm;
    const auto first = std::upper_bound(rest_arc_mm_.begin(), rest_arc_mm_.end(), from_mm);
    const auto last = std::lower_bound(rest_arc_mm_.begin(), rest_arc_mm_.end(), to_mm);
    const auto i0 = static_cast<std::size_t>(
        std::max<std::ptrdiff_t>(0, std::distance(rest_arc_mm_.begin(), first) - 1));
    const auto i1 = std::min(rest_arc_mm_.size() - 1,
                             static_cast<std::size_t>(std::distance(rest_arc_mm_.begin(), last)));
    std::vector<Eigen::Vector3d> points;
    std::vector<double> rest_arc;
    for (std::size_t i = i0; i <= i1; ++i) {
        points.push_back(world.colon_position_mm(i));
        rest_arc.push_back(rest_arc_mm_[i]);
    }
    truth::CenterlinePlace place;
    if (points.size() >= 2)
        place = truth::locate_on_centerline(points, rest_arc, truth::displaced_arc_lengths(points),
                                            world.node_position_mm(world.scope_node_count() - 1),
                                            from_mm, to_mm);
    if (place.found) tip_path_mm_ = place.path_mm;
    o.tip_path_mm = tip_path_mm_;
    std::size_t i = 0;
    while (i + 1 < colon.point_count() && colon.arc_length_mm(i + 1) <= tip_path_mm_)
        ++i;
    o.tip_region = colon.points()[i].region;
    for (const WorldContact& c : world.contacts())
        o.max_wall_force_N = std::max(o.max_wall_force_N, c.normal_force_N);
    return o;
}

PhysicianSource::PhysicianSource(const World& world, const PhysicianSpec& spec,
                                 std::shared_ptr<SceneControl> control)
    : world_(world),
      observer_(world),
      physician_(spec, world.insertion_depth_mm(), world.roll_rad(), world.scope_length_mm()),
      control_(std::move(control)) {
    if (!control_) throw ModelError("physician: no scene control");
    *control_ = SceneControl{};
    control_->steering_gain = physician_.parameters().steering_gain;
    control_->steering_follows_turn = physician_.parameters().steering_follows_turn;
    control_->steering_holds_curvature = physician_.parameters().steering_holds_curvature;
    control_->pressure_stiffness_N_per_mm2 = physician_.parameters().pressure_stiffness_N_per_mm2;
    control_->pressure_max_force_N = physician_.parameters().pressure_max_force_N;
    state_.roll_deg = world.roll_rad() * 180.0 / M_PI;
}

HandleCommand PhysicianSource::command_for_step(std::size_t /*step*/, double t_s, double h_s,
                                                double /*depth_now_mm*/, double /*roll_now_rad*/) {
    const HandDecision d = physician_.decide(observer_.observe(world_), h_s);
    control_->steering = d.steering;
    for (std::size_t r = 0; r < d.pressure.size(); ++r) {
        if (d.pressure[r] && !control_->pressure_since_s[r]) control_->pressure_since_s[r] = t_s;
        if (!d.pressure[r]) control_->pressure_since_s[r].reset();
    }
    state_ = d.state;
    return d.command;
}

std::vector<std::string> PhysicianSource::warnings() const {
    if (physician_.give_up_reason().empty()) return {};
    return {"the physician gave up: " + physician_.give_up_reason()};
}

}  // namespace scopekin::model
