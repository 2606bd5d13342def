#include "model/scenario/abdominal_pressure.hpp"

#include <algorithm>
#include <array>
#include <string>

#include "model/effects/effect_support.hpp"
#include "model/model_error.hpp"

namespace scopekin::model {

namespace {

/// The hand's push on one node, F = -k l excess u, with its stiffness k l u u^T taken implicitly
/// in the world's step (a firm hand on a stiff shaft is a stiff spring: explicit, it would limit
/// the firmness the step can carry). Only the normal part: the turn of u as the node moves
/// sideways adds k l excess/d, a few times smaller where the wall is pushed out by millimetres.
void push_pressure(std::vector<NodalLoad>& loads, const effects::NodeBeyondRestWall& n,
                   double k_N_per_mm2) {
    const double k_N_per_mm = k_N_per_mm2 * n.node_length_mm;
    loads.push_back({n.node, -k_N_per_mm * n.excess_mm * n.outward, Eigen::Vector3d::Zero(),
                     k_N_per_mm * n.outward * n.outward.transpose()});
}

/// One hand over a region gives at most `max_force_N` (|net force| on its nodes): beyond, every
/// force and stiffness of the region is scaled down by the same factor.
void give_way_beyond(double max_force_N, std::vector<NodalLoad>& region_loads) {
    Eigen::Vector3d net_N = Eigen::Vector3d::Zero();
    for (const NodalLoad& l : region_loads)
        net_N += l.force_N;
    const double net_force_N = net_N.norm();
    if (!(net_force_N > max_force_N)) return;
    const double scale = max_force_N / net_force_N;
    for (NodalLoad& l : region_loads) {
        l.force_N *= scale;
        l.stiffness_N_per_mm *= scale;
    }
}

}  // namespace

AbdominalPressure::AbdominalPressure(std::vector<AbdominalPressureWindow> windows)
    : windows_(std::move(windows)) {
    for (std::size_t i = 0; i < windows_.size(); ++i) {
        const AbdominalPressureWindow& w = windows_[i];
        const std::string at = "abdominal_pressure[" + std::to_string(i) + "]";
        require_non_negative(w.start_s, at + ".start_s");
        if (!(w.end_s > w.start_s)) throw ModelError(at + ".end_s: must be later than start_s");
        if (w.regions.empty()) throw ModelError(at + ".regions: name at least one region");
        effects::require_above_at_most(w.stiffness_N_per_mm2, 0.0, 1.0,
                                       at + ".stiffness_N_per_mm2");
        effects::require_in(w.ramp_s, 0.0, w.end_s - w.start_s, at + ".ramp_s");
    }
}

AbdominalPressure::AbdominalPressure(std::shared_ptr<const SceneControl> control)
    : control_(std::move(control)) {
    if (!control_) throw ModelError("abdominal_pressure: no control given");
}

void AbdominalPressure::add_scope_loads(const WorldEffectView& view,
                                        std::vector<NodalLoad>& loads) const {
    if (control_) {
        // Each region's firmness from when the assistant pressed there.
        std::array<double, 8> k_N_per_mm2{};
        bool any = false;
        for (std::size_t r = 0; r < k_N_per_mm2.size(); ++r) {
            const std::optional<double>& since = control_->pressure_since_s[r];
            if (!since) continue;
            const double ramp = control_->pressure_ramp_s;
            const double pressed =
                ramp > 0.0 ? std::clamp((view.time_s - *since) / ramp, 0.0, 1.0) : 1.0;
            k_N_per_mm2[r] = pressed * control_->pressure_stiffness_N_per_mm2;
            any = any || k_N_per_mm2[r] > 0.0;
        }
        if (!any) return;
        std::array<std::vector<NodalLoad>, 8> by_region;
        effects::for_each_node_beyond_rest_wall(
            view, [&](ColonRegion r) { return k_N_per_mm2[static_cast<std::size_t>(r)] > 0.0; },
            [&](const effects::NodeBeyondRestWall& n) {
                const auto r = static_cast<std::size_t>(n.region);
                push_pressure(by_region[r], n, k_N_per_mm2[r]);
            });
        for (std::vector<NodalLoad>& region_loads : by_region) {
            give_way_beyond(control_->pressure_max_force_N, region_loads);
            loads.insert(loads.end(), region_loads.begin(), region_loads.end());
        }
        return;
    }
    const AbdominalPressureWindow* window = nullptr;
    for (const AbdominalPressureWindow& w : windows_)
        if (view.time_s >= w.start_s && view.time_s < w.end_s) window = &w;
    if (window == nullptr) return;
    const double pressed = window->ramp_s > 0.0
                               ? std::min(1.0, (view.time_s - window->start_s) / window->ramp_s)
                               : 1.0;
    const double k_N_per_mm2 = pressed * window->stiffness_N_per_mm2;
    if (!(k_N_per_mm2 > 0.0)) return;  // the hand is only just touching
    const std::vector<ColonRegion>& regions = window->regions;
    effects::for_each_node_beyond_rest_wall(
        view,
        [&](ColonRegion r) {
            return std::find(regions.begin(), regions.end(), r) != regions.end();
        },
        [&](const effects::NodeBeyondRestWall& n) { push_pressure(loads, n, k_N_per_mm2); });
}

}  // namespace scopekin::model
