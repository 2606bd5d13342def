#include "monitors/contact_force_monitor.hpp"

namespace scopekin::monitors {

namespace {

[[nodiscard]] bool saturated(Q16_16 value) noexcept {
    return value == Q16_16::max() || value == Q16_16::min();
}

}  // namespace

bool ContactForceMonitor::valid(const Config& config) noexcept {
    const Q16_16 zero{};
    return config.warning_N > zero && config.warning_N <= config.critical_N &&
           config.critical_N < config.max_valid_force_N && !saturated(config.max_valid_force_N) &&
           config.clear_fraction > zero && config.clear_fraction <= Q16_16::from_int(1) &&
           config.persistence_steps >= 1U && config.persistence_steps <= kMaxPersistenceSteps;
}

bool ContactForceMonitor::init(const Config& config) noexcept {
    const bool ok = valid(config);
    configure(ok ? config : Config{});
    config_fault_ = !ok;
    return ok;
}

void ContactForceMonitor::configure(const Config& config) noexcept {
    config_ = config;
    warning_ =
        Detector{config.warning_N, mul_sat(config.warning_N, config.clear_fraction), 0U, false};
    critical_ =
        Detector{config.critical_N, mul_sat(config.critical_N, config.clear_fraction), 0U, false};
}

void ContactForceMonitor::Detector::update(Q16_16 force, std::uint16_t persistence_steps) noexcept {
    if (active) {
        if (force < clear) {
            active = false;
            count = 0U;
        }
        return;
    }
    if (force >= raise) {
        if (count < persistence_steps) {
            ++count;
        }
        if (count >= persistence_steps) {
            active = true;
            count = 0U;
        }
    } else {
        count = 0U;
    }
}

ContactForceLevel ContactForceMonitor::level() const noexcept {
    if (critical_.active) {
        return ContactForceLevel::critical;
    }
    return warning_.active ? ContactForceLevel::warning : ContactForceLevel::normal;
}

ContactForceMonitor::Outputs ContactForceMonitor::step(Q16_16 max_contact_force_N) noexcept {
    const bool fault = max_contact_force_N < Q16_16{} || saturated(max_contact_force_N) ||
                       max_contact_force_N > config_.max_valid_force_N;
    if (!fault) {
        warning_.update(max_contact_force_N, config_.persistence_steps);
        critical_.update(max_contact_force_N, config_.persistence_steps);
    }
    return Outputs{level(), fault};
}

}  // namespace scopekin::monitors
