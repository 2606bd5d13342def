// tip_odometer.cpp — the EM tracker's tip odometry fused with the handle's estimate (see the
// header for the model, the filter and the fixed-point ranges).
#include "kinetics/tip_odometer.hpp"

#include <algorithm>

#include "messages/em_tracker_samples.hpp"

namespace scopekin::kinetics {
namespace {

using fixed_point::abs_sat;
using fixed_point::add_sat;
using fixed_point::div_sat;
using fixed_point::mul_sat;
using fixed_point::sqrt_sat;
using fixed_point::sub_sat;

constexpr std::size_t kTip = static_cast<std::size_t>(messages::EmSensor::tip);
constexpr std::size_t kSigmoid = static_cast<std::size_t>(messages::EmSensor::sigmoid);

/// The scope's axis, R(q) e_x, from a unit quaternion (w, x, y, z).
std::array<Q16_16, 3> scope_axis(const std::array<Q16_16, 4>& q) noexcept {
    const Q16_16 one = Q16_16::from_int(1);
    const Q16_16 two = Q16_16::from_int(2);
    const Q16_16 w = q[0], x = q[1], y = q[2], z = q[3];
    return {sub_sat(one, mul_sat(two, add_sat(mul_sat(y, y), mul_sat(z, z)))),
            mul_sat(two, add_sat(mul_sat(x, y), mul_sat(w, z))),
            mul_sat(two, sub_sat(mul_sat(x, z), mul_sat(w, y)))};
}

/// (p - previous) . (axis + previous_axis) / 2 [mm]: the mid-interval axis, so a tip that turns
/// between two samples is not measured along either end's axis alone.
Q16_16 advance_along_axis(const std::array<Q16_16, 3>& step_mm, const std::array<Q16_16, 3>& axis,
                          const std::array<Q16_16, 3>& previous_axis) noexcept {
    const Q16_16 half = Q16_16::from_ratio(1, 2);
    Q16_16 sum{};
    for (std::size_t i = 0; i < 3; ++i) {  // bound: 3 components
        sum = add_sat(sum, mul_sat(step_mm[i], mul_sat(half, add_sat(axis[i], previous_axis[i]))));
    }
    return sum;
}

/// |a - b| [mm], saturating at Q16.16's limit (far beyond any bound it is compared with).
Q16_16 distance(const std::array<Q16_16, 3>& a, const std::array<Q16_16, 3>& b) noexcept {
    return fixed_point::hypot_sat(fixed_point::hypot_sat(sub_sat(a[0], b[0]), sub_sat(a[1], b[1])),
                                  sub_sat(a[2], b[2]));
}

bool source_usable(const TrackerInputs& tracker, std::uint8_t source) noexcept {
    return (tracker.valid_mask & source) != 0U && (tracker.stale_mask & source) == 0U;
}

Q16_16 handle_variance(const TipOdometer::Config& config, Q16_16 sd_mm) noexcept {
    const Q16_16 floor_sd = std::max(sd_mm, Q16_16::from_int(1));
    return std::min(mul_sat(floor_sd, floor_sd), config.max_variance_mm2);
}

TipOdometer::Outputs handle_only(const TipOdometer::Inputs& in) noexcept {
    TipOdometer::Outputs out{};
    out.tip_mm = in.handle_tip_mm;
    out.uncertainty_mm = in.handle_sd_mm;
    return out;
}

}  // namespace

bool TipOdometer::Config::valid(Q16_16 period_s) const noexcept {
    if (q_mm2_per_mm < Q16_16{} || !(correlation_s > Q16_16{})) return false;
    if (update_steps < 1U || update_steps > 1000U || sigmoid_reach_mm < Q16_16{}) return false;
    if (max_variance_mm2 < Q16_16::from_int(1) || max_variance_mm2 > Q16_16::from_int(30000))
        return false;
    // correlation_s / T must fit the gain's arithmetic (header, "Fixed point").
    const Q16_16 update_s = mul_sat(period_s, Q16_16::from_int(update_steps));
    return update_s > Q16_16{} && div_sat(correlation_s, update_s) < Q16_16::from_int(32767);
}

TipOdometer::Outputs TipOdometer::step(const Config& config, const Inputs& in,
                                       State& state) noexcept {
    const TrackerInputs* tracker = in.tracker;
    const bool tip_stale = tracker == nullptr ||
                           (tracker->stale_mask & messages::kEmSourceTip) != 0U ||
                           (tracker->valid_mask & messages::kEmSourceTip) == 0U;
    if (!config.enabled || tip_stale) {
        state.running = false;
        return handle_only(in);
    }
    const bool fresh = (tracker->fresh_mask & messages::kEmSourceTip) != 0U;
    const messages::EmPoseSample& pose = tracker->pose[kTip];
    if (!state.running) {
        if (!fresh) return handle_only(in);
        state.running = true;
        state.last_position_mm = pose.position_mm;
        state.last_axis = scope_axis(pose.orientation);
        state.sigmoid_seen = source_usable(*tracker, messages::kEmSourceSigmoid);
        state.last_sigmoid_mm = tracker->pose[kSigmoid].position_mm;
        state.tip_mm = in.handle_tip_mm;
        state.variance_mm2 = handle_variance(config, in.handle_sd_mm);
        state.steps_since_update = 0;
        Outputs out{};
        out.active = true;
        out.travel_mm = state.travel_mm;
        out.tip_mm = std::clamp(state.tip_mm, in.tip_min_mm, in.tip_max_mm);
        out.uncertainty_mm = sqrt_sat(state.variance_mm2);
        state.tip_mm = out.tip_mm;
        return out;
    }
    if (fresh) {
        // Predict: the tip's advance along its own axis, relative to the sigmoid when the tip is
        // near the sensor sutured on it (a carried sigmoid is no advance).
        std::array<Q16_16, 3> step_mm{};
        for (std::size_t i = 0; i < 3; ++i) {  // bound: 3 components
            step_mm[i] = sub_sat(pose.position_mm[i], state.last_position_mm[i]);
        }
        const bool sigmoid_now = source_usable(*tracker, messages::kEmSourceSigmoid);
        const std::array<Q16_16, 3>& sigmoid_mm = tracker->pose[kSigmoid].position_mm;
        if (sigmoid_now && state.sigmoid_seen &&
            distance(pose.position_mm, sigmoid_mm) < config.sigmoid_reach_mm) {
            for (std::size_t i = 0; i < 3; ++i) {  // bound: 3 components
                step_mm[i] = sub_sat(step_mm[i], sub_sat(sigmoid_mm[i], state.last_sigmoid_mm[i]));
            }
        }
        const std::array<Q16_16, 3> axis = scope_axis(pose.orientation);
        const Q16_16 dx = advance_along_axis(step_mm, axis, state.last_axis);
        state.last_position_mm = pose.position_mm;
        state.last_axis = axis;
        state.sigmoid_seen = sigmoid_now;
        state.last_sigmoid_mm = sigmoid_mm;
        state.tip_mm = add_sat(state.tip_mm, dx);
        state.travel_mm = add_sat(state.travel_mm, dx);
        state.variance_mm2 =
            std::min(add_sat(state.variance_mm2, mul_sat(config.q_mm2_per_mm, abs_sat(dx))),
                     config.max_variance_mm2);
    }
    if (in.handle_trusted) {
        state.tip_mm = in.handle_tip_mm;
        state.variance_mm2 = handle_variance(config, in.handle_sd_mm);
        state.steps_since_update = 0;
    } else if (++state.steps_since_update >= config.update_steps) {
        // Update with the handle's estimate, as T / correlation_s of an independent measurement.
        state.steps_since_update = 0;
        const Q16_16 ratio = div_sat(state.variance_mm2, handle_variance(config, in.handle_sd_mm));
        const Q16_16 update_s = mul_sat(in.period_s, Q16_16::from_int(config.update_steps));
        const Q16_16 gain = div_sat(ratio, add_sat(ratio, div_sat(config.correlation_s, update_s)));
        state.tip_mm =
            add_sat(state.tip_mm, mul_sat(gain, sub_sat(in.handle_tip_mm, state.tip_mm)));
        state.variance_mm2 = mul_sat(state.variance_mm2, sub_sat(Q16_16::from_int(1), gain));
    }
    state.tip_mm = std::clamp(state.tip_mm, in.tip_min_mm, in.tip_max_mm);
    Outputs out{};
    out.active = true;
    out.fresh = fresh;
    out.tip_mm = state.tip_mm;
    out.uncertainty_mm = sqrt_sat(state.variance_mm2);
    out.travel_mm = state.travel_mm;
    return out;
}

}  // namespace scopekin::kinetics
