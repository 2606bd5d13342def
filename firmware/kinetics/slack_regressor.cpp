// The slack regressor's step (slack_regressor.hpp). Q16.16 features, 64-bit averages and sums;
// scaling in the header.
#include "kinetics/slack_regressor.hpp"

#include <algorithm>

namespace scopekin::kinetics {

namespace {

constexpr Q16_16 kCumulativeCap_mm = Q16_16::from_int(30000);
constexpr std::int64_t kRawMax = INT32_MAX;
constexpr std::int64_t kRawMin = INT32_MIN;

Q16_16 saturated(std::int64_t raw) noexcept {
    return Q16_16::from_raw(static_cast<std::int32_t>(std::clamp(raw, kRawMin, kRawMax)));
}

/// acc (Q31.32) moved by alpha towards x; returns the average as Q16.16 (rounded down).
Q16_16 average(std::int64_t& acc_q32, Q16_16 x, std::int32_t alpha_raw) noexcept {
    const std::int64_t difference_raw = static_cast<std::int64_t>(x.raw()) - (acc_q32 >> 16);
    acc_q32 += difference_raw * alpha_raw;
    return saturated(acc_q32 >> 16);
}

Q16_16 add_capped(Q16_16 total, Q16_16 amount) noexcept {
    return std::min(total + amount, kCumulativeCap_mm);
}

}  // namespace

bool SlackTrees::valid() const noexcept {
    if (tree_count < 1 || tree_count > kMaxSlackTrees || depth < 1 || depth > kMaxSlackTreeDepth)
        return false;
    if (feature == nullptr || threshold_raw == nullptr || leaf_raw == nullptr) return false;
    const std::size_t nodes = tree_count * ((std::size_t{1} << depth) - 1U);
    for (std::size_t i = 0; i < nodes; ++i)  // bound: kMaxSlackTrees * 255
        if (feature[i] >= kSlackFeatureCount) return false;
    for (const std::int32_t tau : average_tau_s_raw)
        if (tau <= 0) return false;
    return sigma_floor_raw >= 0 && sigma_per_prediction_raw >= 0 && sigma_per_metre_raw >= 0;
}

bool same_features(const SlackTrees& a, const SlackTrees& b) noexcept {
    for (std::size_t k = 0; k < kSlackAverages; ++k)  // bound: kSlackAverages
        if (a.average_tau_s_raw[k] != b.average_tau_s_raw[k]) return false;
    return true;
}

Q16_16 SlackRegressor::predict(const SlackTrees& trees,
                               const Q16_16 (&features)[kSlackFeatureCount]) noexcept {
    const std::size_t internal = (std::size_t{1} << trees.depth) - 1U;
    std::int64_t sum = trees.base_raw;
    for (std::size_t t = 0; t < trees.tree_count; ++t) {  // bound: kMaxSlackTrees
        const std::uint8_t* feature = trees.feature + t * internal;
        const std::int32_t* threshold = trees.threshold_raw + t * internal;
        std::size_t node = 0;
        for (std::size_t level = 0; level < trees.depth; ++level)  // bound: kMaxSlackTreeDepth
            node =
                features[feature[node]].raw() <= threshold[node] ? 2U * node + 1U : 2U * node + 2U;
        sum += trees.leaf_raw[t * (internal + 1U) + (node - internal)];
    }
    return saturated(sum);
}

SlackRegressor::Outputs SlackRegressor::step(const SlackTrees& trees, const Inputs& inputs,
                                             State& state) noexcept {
    if (!state.started) {
        state = State{};
        state.started = true;
        state.last_depth_mm = inputs.depth_mm;
        state.deepest_mm = inputs.depth_mm;
        for (std::size_t k = 0; k < kSlackAverages; ++k)  // bound: kSlackAverages
            state.force_ema_q32[k] = static_cast<std::int64_t>(inputs.handle_force_N.raw()) << 16;
    }
    const Q16_16 moved_mm = inputs.depth_mm - state.last_depth_mm;
    state.last_depth_mm = inputs.depth_mm;
    if (moved_mm > Q16_16{}) state.advanced_mm = add_capped(state.advanced_mm, moved_mm);
    if (moved_mm < Q16_16{}) state.withdrawn_mm = add_capped(state.withdrawn_mm, -moved_mm);
    state.deepest_mm = std::max(state.deepest_mm, inputs.depth_mm);
    const Q16_16 speed_mm_per_s = moved_mm / inputs.period_s;

    Outputs out{};
    out.features[kSlackDepth] = inputs.depth_mm;
    out.features[kSlackHandleForce] = inputs.handle_force_N;
    out.features[kSlackAdvanced] = state.advanced_mm;
    out.features[kSlackWithdrawn] = state.withdrawn_mm;
    out.features[kSlackBelowDeepest] = state.deepest_mm - inputs.depth_mm;
    out.features[kSlackObserverSlack] = inputs.observer_slack_mm;
    for (std::size_t k = 0; k < kSlackAverages; ++k) {  // bound: kSlackAverages
        const Q16_16 tau_s = Q16_16::from_raw(trees.average_tau_s_raw[k]);
        const std::int32_t alpha_raw = std::min(inputs.period_s / tau_s, Q16_16::from_int(1)).raw();
        out.features[kSlackForceEma1s + k] =
            inputs.force_fresh ? average(state.force_ema_q32[k], inputs.handle_force_N, alpha_raw)
                               : saturated(state.force_ema_q32[k] >> 16);
        out.features[kSlackSpeedEma1s + k] =
            average(state.speed_ema_q32[k], speed_mm_per_s, alpha_raw);
    }
    out.slack_mm = predict(trees, out.features);
    out.uncertainty_mm = uncertainty(trees, out.slack_mm, inputs.depth_mm);
    return out;
}

Q16_16 SlackRegressor::uncertainty(const SlackTrees& trees, Q16_16 prediction,
                                   Q16_16 depth_mm) noexcept {
    const Q16_16 magnitude = prediction < Q16_16{} ? -prediction : prediction;
    return Q16_16::from_raw(trees.sigma_floor_raw) +
           Q16_16::from_raw(trees.sigma_per_prediction_raw) * magnitude +
           Q16_16::from_raw(trees.sigma_per_metre_raw) * (depth_mm / Q16_16::from_int(1000));
}

}  // namespace scopekin::kinetics
