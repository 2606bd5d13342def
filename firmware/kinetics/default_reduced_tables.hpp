// default_reduced_tables.hpp — the reduced model generated from the bundled training runs
// (model/reduction/training.json) by model/reduction at build time; library
// scopekin::firmware_tables.  Host builds generate it; cross builds compile the committed copy
// firmware/kinetics/generated/default_reduced_tables.cpp, which a host test keeps identical to
// what the generator writes (update: cmake --build build/host --target update_reduced_tables).
#pragma once

#include "kinetics/kinetics.hpp"
#include "kinetics/reduced_tables.hpp"

namespace scopekin::kinetics {

using fixed_point::Q16_16;

[[nodiscard]] const ReducedTablesQ16& default_reduced_tables() noexcept;

/// Config{} with the default tables, the fitted slack regressor, contact force trees and loop
/// alarm.
[[nodiscard]] inline Config default_config() noexcept {
    Config config{};
    config.tables = &default_reduced_tables();
    config.slack_trees = &default_slack_trees();
    config.contact_force_trees = &default_contact_force_trees();
    config.loop_alarm_trees = &default_loop_alarm_trees();
    config.loop_alarm = default_loop_alarm();
    return config;
}

}  // namespace scopekin::kinetics
