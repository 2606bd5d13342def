#include "monitors/self_lock_monitor.hpp"

namespace scopekin::monitors {

namespace {

[[nodiscard]] bool saturated(Q16_16 value) noexcept {
    return value == Q16_16::max() || value == Q16_16::min();
}

[[nodiscard]] bool valid_force(Q16_16 force, const StickCriterion& criterion) noexcept {
    return force >= Q16_16{} && !saturated(force) && force <= criterion.max_valid_force_N;
}

/// Efficiency values AdvanceEfficiency can produce: [-2, 2].
[[nodiscard]] bool valid_efficiency(Q16_16 efficiency) noexcept {
    return efficiency >= Q16_16::from_int(-2) && efficiency <= Q16_16::from_int(2);
}

}  // namespace

bool valid(const StickCriterion& criterion) noexcept {
    const Q16_16 zero{};
    return criterion.stick_ratio > zero && criterion.stick_ratio <= Q16_16::from_int(1) &&
           criterion.min_normal_force_N >= zero &&
           criterion.min_normal_force_N < criterion.max_valid_force_N &&
           criterion.max_valid_force_N < Q16_16::from_int(32767) && criterion.max_valid_mu > zero &&
           criterion.max_valid_mu <= Q16_16::from_int(2);
}

StickState classify_stick(Q16_16 normal_N, Q16_16 tangential_N, Q16_16 mu,
                          const StickCriterion& criterion) noexcept {
    if (!valid(criterion) || !valid_force(normal_N, criterion) ||
        !valid_force(tangential_N, criterion) || mu < Q16_16{} || mu > criterion.max_valid_mu) {
        return StickState::invalid;
    }
    if (normal_N < criterion.min_normal_force_N || normal_N == Q16_16{}) {
        return StickState::no_contact;
    }
    // alpha < beta  <=>  |f_T| < mu f_n; with the margin: |f_T| < (stick_ratio * mu) * f_n,
    // compared exactly in 64 bits (see "Scaling and overflow").
    const Q16_16 mu_eff = mul_sat(criterion.stick_ratio, mu);
    const std::int64_t lhs = std::int64_t{tangential_N.raw()} * Q16_16::one_raw;
    const std::int64_t rhs = std::int64_t{mu_eff.raw()} * normal_N.raw();
    return lhs < rhs ? StickState::sticking : StickState::slipping;
}

bool SelfLockMonitor::valid(const Config& config) noexcept {
    const Q16_16 zero{};
    return config.min_sticking_stations >= 1U &&
           config.min_sticking_stations <= config.max_distal_stations && config.on_steps >= 1U &&
           config.on_steps <= kMaxHysteresisSteps && config.off_steps >= 1U &&
           config.off_steps <= kMaxHysteresisSteps && config.confirm_efficiency > zero &&
           config.confirm_efficiency <= config.clear_efficiency &&
           config.clear_efficiency <= Q16_16::from_int(2);
}

bool SelfLockMonitor::init(const Config& config) noexcept {
    const bool ok = valid(config);
    config_ = ok ? config : Config{};
    config_fault_ = !ok;
    last_ = Outputs{};
    off_count_ = 0U;
    return ok;
}

SelfLockMonitor::Outputs SelfLockMonitor::step(const Inputs& inputs) noexcept {
    if (inputs.distal_sticking > config_.max_distal_stations ||
        !valid_efficiency(inputs.efficiency)) {
        Outputs held = last_;
        held.input_fault = true;
        return held;
    }

    Outputs out{};
    out.condition =
        inputs.distal_sticking >= config_.min_sticking_stations && inputs.handle_advancing;
    if (out.condition) {
        out.condition_steps = last_.condition_steps < config_.on_steps
                                  ? static_cast<std::uint16_t>(last_.condition_steps + 1U)
                                  : config_.on_steps;
    }

    out.alarm = last_.alarm;
    if (!out.alarm) {
        if (out.condition_steps >= config_.on_steps) {
            out.alarm = true;
            off_count_ = 0U;
        }
    } else {
        if (out.condition) {
            off_count_ = 0U;
        } else if (off_count_ < config_.off_steps) {
            ++off_count_;
        }
        const bool tip_follows =
            inputs.efficiency_defined && inputs.efficiency >= config_.clear_efficiency;
        if (off_count_ >= config_.off_steps && tip_follows) {
            out.alarm = false;
            off_count_ = 0U;
        }
    }
    out.confirmed =
        out.alarm && inputs.efficiency_defined && inputs.efficiency < config_.confirm_efficiency;
    last_ = out;
    return out;
}

}  // namespace scopekin::monitors
