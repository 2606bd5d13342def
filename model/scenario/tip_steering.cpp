#include "model/scenario/tip_steering.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/model_error.hpp"

namespace scopekin::model {

TipSteering::TipSteering(std::vector<SteeringWindow> windows, const ColonTube& colon,
                         double bending_stiffness_Nmm2, double element_mm)
    : windows_(std::move(windows)),
      colon_(colon),
      ei_Nmm2_(bending_stiffness_Nmm2),
      element_mm_(element_mm) {
    for (std::size_t i = 0; i < windows_.size(); ++i) {
        const SteeringWindow& w = windows_[i];
        const std::string at = "steering[" + std::to_string(i) + "]";
        require_non_negative(w.start_s, at + ".start_s");
        if (!(w.end_s > w.start_s)) throw ModelError(at + ".end_s: must be later than start_s");
        require_positive(w.lookahead_mm, at + ".lookahead_mm");
        require_positive(w.bending_section_mm, at + ".bending_section_mm");
        if (!(w.gain > 0.0 && w.gain <= 1.0)) throw ModelError(at + ".gain: must be in (0, 1]");
    }
}

TipSteering::TipSteering(std::shared_ptr<const SceneControl> control, const ColonTube& colon,
                         double bending_stiffness_Nmm2, double element_mm)
    : control_(std::move(control)),
      colon_(colon),
      ei_Nmm2_(bending_stiffness_Nmm2),
      element_mm_(element_mm) {
    if (!control_) throw ModelError("tip_steering: no control given");
}

const SteeringWindow* TipSteering::active_window(const WorldEffectView& view,
                                                 SteeringWindow& switched) const {
    const SteeringWindow* window = nullptr;
    for (const SteeringWindow& w : windows_)
        if (view.time_s >= w.start_s && view.time_s < w.end_s) window = &w;
    if (control_ && control_->steering) {
        switched.lookahead_mm = control_->steering_lookahead_mm;
        switched.bending_section_mm = control_->steering_bending_section_mm;
        switched.gain = control_->steering_gain;
        switched.follows_turn = control_->steering_follows_turn;
        switched.holds_curvature = control_->steering_holds_curvature;
        window = &switched;
    }
    return window;
}

void TipSteering::track_tip(const WorldEffectView& view) const {
    if (view.time_s == tracked_at_s_) return;
    tracked_at_s_ = view.time_s;
    // Track the tip along the centerline (a window around its last place keeps it off other turns
    // of a loop); the tracking runs outside steering windows too.
    if (tip_path_mm_ < 0) tip_path_mm_ = std::max(0.0, view.insertion_depth_mm);
    double path = 0;
    std::size_t segment = 0;
    if (colon_.closest_point_near(view.scope_nodes_mm.back(), tip_path_mm_, 60.0, path, segment))
        tip_path_mm_ = path;
}

Eigen::Vector3d TipSteering::wanted_direction(const WorldEffectView& view,
                                              const SteeringWindow& window) const {
    const Eigen::Vector3d& x_tip = view.scope_nodes_mm.back();
    const double target = std::min(tip_path_mm_ + window.lookahead_mm, colon_.length_mm());
    std::size_t j = 0;
    while (j + 1 < colon_.point_count() && colon_.arc_length_mm(j) < target)
        ++j;
    Eigen::Vector3d wanted = (colon_.points()[j].position_mm - x_tip).normalized();
    if (window.follows_turn && j + 1 < colon_.point_count())
        wanted =
            (wanted +
             (colon_.points()[j + 1].position_mm - colon_.points()[j].position_mm).normalized())
                .normalized();
    return wanted;
}

std::size_t TipSteering::section_elements(const SteeringWindow& window) const {
    return static_cast<std::size_t>(
        std::max(1L, std::lround(window.bending_section_mm / element_mm_)));
}

void TipSteering::add_scope_loads(const WorldEffectView& view,
                                  std::vector<NodalLoad>& loads) const {
    const std::size_t nodes = view.scope_nodes_mm.size();
    if (nodes < 3) return;
    track_tip(view);
    SteeringWindow switched;
    const SteeringWindow* window = active_window(view, switched);
    if (window == nullptr || window->holds_curvature) return;

    const std::size_t tip = nodes - 1;
    const Eigen::Vector3d axis =
        (view.scope_nodes_mm[tip] - view.scope_nodes_mm[tip - 1]).normalized();
    const Eigen::Vector3d wanted = wanted_direction(view, *window);
    Eigen::Vector3d b = axis.cross(wanted);
    const double sine = b.norm();
    if (!(sine > 1e-9)) return;
    b /= sine;
    const double theta = std::min(std::atan2(sine, axis.dot(wanted)), M_PI);
    const std::size_t back = section_elements(*window);
    if (back >= tip) return;
    const double moment_Nmm = window->gain * ei_Nmm2_ * theta / window->bending_section_mm;
    loads.push_back({tip, Eigen::Vector3d::Zero(), moment_Nmm * b});
    loads.push_back({tip - back, Eigen::Vector3d::Zero(), -moment_Nmm * b});
}

void TipSteering::add_rest_curvature(const WorldEffectView& view,
                                     std::vector<Eigen::Vector3d>& curvature_per_mm) const {
    const std::size_t nodes = view.scope_nodes_mm.size();
    if (nodes < 3 || curvature_per_mm.size() + 1 != nodes) return;
    track_tip(view);
    SteeringWindow switched;
    const SteeringWindow* window = active_window(view, switched);
    const std::size_t tip = nodes - 1;
    // What the wheels are turned towards: the section's bend that points the tip along the
    // wanted direction (from the section's base), or straight when the hand lets go.
    Eigen::Vector3d target = Eigen::Vector3d::Zero();
    double section_mm = static_cast<double>(held_elements_) * element_mm_;
    if (window != nullptr && window->holds_curvature && section_elements(*window) < tip) {
        held_elements_ = section_elements(*window);
        section_mm = window->bending_section_mm;
        const Eigen::Vector3d& base_axis = view.scope_axes[tip - held_elements_];
        const Eigen::Vector3d wanted = wanted_direction(view, *window);
        Eigen::Vector3d b = base_axis.cross(wanted);
        const double sine = b.norm();
        if (sine > 1e-9) {
            const double theta = std::min(std::atan2(sine, base_axis.dot(wanted)), M_PI);
            target = (window->gain * theta / section_mm / sine) * b;
        }
    }
    if (held_elements_ == 0) return;
    if (view.time_s != turned_at_s_) {  // a retried step does not turn the wheels again
        turned_at_s_ = view.time_s;
        turned_from_per_mm_ = held_curvature_per_mm_;
    }
    Eigen::Vector3d change = target - turned_from_per_mm_;
    const double most = kWheelRate_rad_per_s * view.time_step_s / section_mm;
    if (change.norm() > most) change *= most / change.norm();
    held_curvature_per_mm_ = turned_from_per_mm_ + change;
    for (std::size_t e = tip - held_elements_; e < tip; ++e)
        curvature_per_mm[e] += held_curvature_per_mm_;
}

}  // namespace scopekin::model
