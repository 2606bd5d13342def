#include "model/colon/colon_pleating.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "model/model_error.hpp"

namespace scopekin::model {

namespace {
/// Shape solve: bisections of the blend between chord and curve (2^-40: exact to the double).
constexpr int kShapeBisections = 40;
/// Pleats per step at most: the law is explicit, this keeps it stable at any rate x drag.
constexpr double kMaxFractionPerStep = 0.01;
/// The chain must stay longer than its chord: p_max is capped at this share of (1 - chord/L).
constexpr double kChordRoomUsed = 0.9;
}  // namespace

void TelescopingLaw::validate() const {
    require_non_negative(onset_drag_N, "telescoping.onset_drag_N");
    require_positive(stiffening_drag_N, "telescoping.stiffening_drag_N");
    require_positive(recoil_time_s, "telescoping.recoil_time_s");
    require_positive(rate_per_N_s, "telescoping.rate_per_N_s");
    if (!(max_fraction >= 0.0 && max_fraction < 1.0))
        throw ModelError("telescoping.max_fraction: " + std::to_string(max_fraction) +
                         " must be in [0, 1)");
}

ColonPleating::ColonPleating(std::vector<Eigen::Vector3d> rest_mm, const std::vector<bool>& mobile,
                             TelescopingLaw law)
    : rest_mm_(std::move(rest_mm)), law_(law) {
    law_.validate();
    if (mobile.size() != rest_mm_.size())
        throw ModelError("telescoping: one mobile flag per colon node is needed");
    for (std::size_t j = 0; j + 1 < rest_mm_.size(); ++j)
        segment_mm_.push_back((rest_mm_[j + 1] - rest_mm_[j]).norm());
    for (std::size_t i = 1; i + 1 < rest_mm_.size(); ++i) {
        if (!mobile[i] || mobile[i - 1]) continue;
        Stretch s;
        s.first = i;
        s.last = i;
        while (s.last + 2 < rest_mm_.size() && mobile[s.last + 1])
            ++s.last;
        for (std::size_t j = s.first - 1; j <= s.last; ++j)
            s.length_mm += segment_mm_[j];
        const double chord = (rest_mm_[s.last + 1] - rest_mm_[s.first - 1]).norm();
        s.max_fraction = std::max(
            0.0, std::min(law_.max_fraction, kChordRoomUsed * (1.0 - chord / s.length_mm)));
        stretches_.push_back(s);
    }
    state_.fraction.assign(stretches_.size(), 0.0);
    state_.position_mm = rest_mm_;
    state_.last_motion_mm.assign(rest_mm_.size(), Eigen::Vector3d::Zero());
}

void ColonPleating::restore(const State& s) {
    if (s.fraction.size() != stretches_.size() || s.position_mm.size() != rest_mm_.size() ||
        s.last_motion_mm.size() != rest_mm_.size())
        throw ModelError("restore: the saved telescoping state is of another colon");
    state_ = s;
}

double ColonPleating::length_now_mm(std::size_t k) const {
    double l = 0.0;
    for (std::size_t j = stretches_[k].first - 1; j <= stretches_[k].last; ++j)
        l += (state_.position_mm[j + 1] - state_.position_mm[j]).norm();
    return l;
}

std::vector<double> ColonPleating::drag_towards_anus_N(
    const std::vector<ColonPointForce>& forces) const {
    std::vector<double> drag(stretches_.size(), 0.0);
    for (const ColonPointForce& f : forces) {
        if (f.segment + 1 >= state_.position_mm.size()) continue;
        const Eigen::Vector3d towards_anus =
            (state_.position_mm[f.segment] - state_.position_mm[f.segment + 1]).normalized();
        for (std::size_t k = 0; k < stretches_.size(); ++k)
            if (f.segment + 1 >= stretches_[k].first && f.segment <= stretches_[k].last)
                drag[k] += f.force_N.dot(towards_anus);
    }
    return drag;
}

double ColonPleating::rate_per_s(std::size_t k, double p, double drag_N) const {
    const double q = std::min(p / stretches_[k].max_fraction, 0.999);
    const double resistance_N = law_.onset_drag_N + law_.stiffening_drag_N * q / (1.0 - q);
    if (drag_N > resistance_N) return law_.rate_per_N_s * (drag_N - resistance_N);
    if (std::abs(drag_N) < law_.onset_drag_N) return -p / law_.recoil_time_s;
    return 0.0;  // held on the scope
}

bool ColonPleating::advance(const std::vector<ColonPointForce>& forces, double h_s) {
    std::fill(state_.last_motion_mm.begin(), state_.last_motion_mm.end(), Eigen::Vector3d::Zero());
    if (!law_.enabled) return false;
    const std::vector<double> drag = drag_towards_anus_N(forces);
    bool moved = false;
    for (std::size_t k = 0; k < stretches_.size(); ++k) {
        const double p_max = stretches_[k].max_fraction;
        if (p_max <= 0.0) continue;
        const double p = state_.fraction[k];
        // Explicit step, at most kMaxFractionPerStep: stable at any rate x drag.
        const double step =
            std::clamp(rate_per_s(k, p, drag[k]) * h_s, -kMaxFractionPerStep, kMaxFractionPerStep);
        const double next = std::clamp(p + step, 0.0, p_max);
        if (next == p) continue;
        const std::vector<Eigen::Vector3d> before(
            state_.position_mm.begin() + static_cast<long>(stretches_[k].first),
            state_.position_mm.begin() + static_cast<long>(stretches_[k].last + 1));
        state_.fraction[k] = next;
        solve_shape(k, next);
        for (std::size_t i = stretches_[k].first; i <= stretches_[k].last; ++i)
            state_.last_motion_mm[i] = state_.position_mm[i] - before[i - stretches_[k].first];
        moved = true;
    }
    return moved;
}

void ColonPleating::solve_shape(std::size_t k, double p) {
    const Stretch& s = stretches_.at(k);
    std::vector<Eigen::Vector3d>& x = state_.position_mm;
    // Blend lambda in [0, 1] between the chord (0) and the unpleated curve (1), each node at its
    // arc fraction, by bisection on the length: the length grows with lambda from the chord's.
    const Eigen::Vector3d a = rest_mm_[s.first - 1], b = rest_mm_[s.last + 1];
    const double target = (1.0 - p) * s.length_mm;
    auto place = [&](double lambda) {
        double arc = 0.0;
        for (std::size_t i = s.first; i <= s.last; ++i) {
            arc += segment_mm_[i - 1];
            const Eigen::Vector3d on_chord = a + (arc / s.length_mm) * (b - a);
            x[i] = on_chord + lambda * (rest_mm_[i] - on_chord);
        }
    };
    double lo = 0.0, hi = 1.0;
    for (int it = 0; it < kShapeBisections; ++it) {
        const double mid = 0.5 * (lo + hi);
        place(mid);
        (length_now_mm(k) < target ? lo : hi) = mid;
    }
    place(p <= 0.0 ? 1.0 : 0.5 * (lo + hi));
}

}  // namespace scopekin::model
