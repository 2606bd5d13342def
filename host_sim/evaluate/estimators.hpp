#pragma once
// The estimators a scorecard scores on every case (host_sim/evaluate/README.md, "Estimators"):
// each gives, at the box's periods, what it publishes — the tip along the colon, the largest
// contact force, a loop alarm, a contact level (0/1/2) and fault flags — or leaves a quantity
// out (an empty series: "n/a" in the tables).
//
// Adding one is one entry in estimator_registry(): a name, a label for the tables, and a
// function from the case's run folder (CaseRun) to its outputs. A firmware variant (issue 21's
// estimator) is scored from its own firmware CSV: the world does not depend on the box, so the
// case's recording.csv run through the variant (`scopekin run`, the variant selected by a
// sensor-box configuration key) gives its outputs on the same case.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "host_sim/evaluate/case_run.hpp"
#include "host_sim/evaluate/force_monitor.hpp"

namespace scopekin::evaluate {

struct EstimatorOutput {
    std::vector<double> tip_path_mm;         ///< empty: not estimated
    std::vector<double> tip_uncertainty_mm;  ///< one SD of tip_path_mm; empty: not stated
    std::vector<double> max_force_N;         ///< empty: not estimated
    std::vector<std::uint8_t> loop_alarm;
    std::vector<std::uint8_t> contact_level;  ///< 0 normal, 1 warning (>= 10 N), 2 critical
    std::vector<std::uint32_t> fault_flags;   ///< kinetics FaultFlag bits; empty: none
};

struct EstimatorContext {
    ForceMonitorThresholds force_monitor;
};

struct Estimator {
    std::string name;   ///< a column-safe id: "depth_replay", "force_monitor"
    std::string label;  ///< for the tables
    std::function<EstimatorOutput(const CaseRun&, const EstimatorContext&)> outputs;
};

/// The estimators in the order the tables show them.
const std::vector<Estimator>& estimator_registry();

/// Every registered estimator's outputs on a complete case, in the registry's order.
std::vector<EstimatorOutput> estimator_outputs(const CaseRun& run, const EstimatorContext& context);

/// Names of the kinetics fault flag bits (firmware/kinetics/kinetics_io.hpp FaultFlag).
const std::vector<std::string>& fault_flag_names();

}  // namespace scopekin::evaluate
