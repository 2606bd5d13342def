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

void TipSteering::add_scope_loads(const WorldEffectView& view,
                                  std::vector<NodalLoad>& loads) const {
    const SteeringWindow* window = nullptr;
    for (const SteeringWindow& w : windows_)
        if (view.time_s >= w.start_s && view.time_s < w.end_s) window = &w;
    SteeringWindow switched;
    if (control_ && control_->steering) {
        switched.lookahead_mm = control_->steering_lookahead_mm;
        switched.bending_section_mm = control_->steering_bending_section_mm;
        switched.gain = control_->steering_gain;
        switched.follows_turn = control_->steering_follows_turn;
        window = &switched;
    }
    const std::size_t nodes = view.scope_nodes_mm.size();
    if (nodes < 3) return;
    const std::size_t tip = nodes - 1;
    const Eigen::Vector3d x_tip = view.scope_nodes_mm[tip];
    // Track the tip along the centerline (a window around its last place keeps it off other turns
    // of a loop); the tracking runs outside steering windows too.
    if (tip_path_mm_ < 0) tip_path_mm_ = std::max(0.0, view.insertion_depth_mm);
    double path = 0;
    std::size_t segment = 0;
    if (colon_.closest_point_near(x_tip, tip_path_mm_, 60.0, path, segment)) tip_path_mm_ = path;
    if (window == nullptr) return;

    const double target = std::min(tip_path_mm_ + window->lookahead_mm, colon_.length_mm());
    std::size_t j = 0;
    while (j + 1 < colon_.point_count() && colon_.arc_length_mm(j) < target)
        ++j;
    const Eigen::Vector3d axis = (x_tip - view.scope_nodes_mm[tip - 1]).normalized();
    Eigen::Vector3d wanted = (colon_.points()[j].position_mm - x_tip).normalized();
    if (window->follows_turn && j + 1 < colon_.point_count())
        wanted =
            (wanted +
             (colon_.points()[j + 1].position_mm - colon_.points()[j].position_mm).normalized())
                .normalized();
    Eigen::Vector3d b = axis.cross(wanted);
    const double sine = b.norm();
    if (!(sine > 1e-9)) return;
    b /= sine;
    const double theta = std::min(std::atan2(sine, axis.dot(wanted)), M_PI);
    const auto back = static_cast<std::size_t>(
        std::max(1L, std::lround(window->bending_section_mm / element_mm_)));
    if (back >= tip) return;
    const double moment_Nmm = window->gain * ei_Nmm2_ * theta / window->bending_section_mm;
    loads.push_back({tip, Eigen::Vector3d::Zero(), moment_Nmm * b});
    loads.push_back({tip - back, Eigen::Vector3d::Zero(), -moment_Nmm * b});
}

}  // namespace scopekin::model
