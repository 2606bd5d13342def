#pragma once
// Baseline (b) of the scorecard: what a handle force monitor alone can do (the view of the
// Colonoscopy Force Monitor, a handle force display with alarms). It sees only what the box's
// handle sensors deliver (recording.csv: the measured push force and the insertion depth, with
// their noise) and raises
//  * a loop alarm when, while the hand advances (>= 1 mm over the trailing 0.5 s), the push
//    force reaches `loop.force_N` or its rate reaches `loop.rate_N_per_s`; it clears once force
//    and rate have both stayed below kClearFraction of their thresholds for kLoopClearHold_s;
//  * contact alarms: level 1 while the push force is >= `warning_N`, level 2 while >=
//    `critical_N`, each clearing below kClearFraction of its threshold (the firmware's band).
// Thresholds are tuned on the development set only (tune_force_monitor, `scopekin
// evaluate-tune`) and read from host_sim/evaluate/force_monitor_thresholds.json.
// host_sim/evaluate/README.md, "The handle force monitor", states every constant and why.
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/evaluate/case_run.hpp"
#include "host_sim/evaluate/scoring.hpp"
#include "model/truth/truth_definitions.hpp"

namespace scopekin::evaluate {

/// The push force is the mean of the handle force samples over this trailing window [s]: a
/// display's smoothing (stated guess; 50 samples at 1 kHz average the 0.02 N noise down to
/// 0.003 N).
inline constexpr double kForceWindow_s = 0.05;
/// The force rate is the change of that mean over this trailing window [s] divided by it.
inline constexpr double kRateWindow_s = 0.25;
/// Advancing: the insertion grew by at least kAdvanceMin_mm over kAdvanceWindow_s (the truth's
/// pace rule, model/truth/README.md).
inline constexpr double kAdvanceWindow_s = model::truth::kPaceWindow_s;
inline constexpr double kAdvanceMin_mm = model::truth::kPaceMinHandle_mm;
/// Hysteresis: an alarm clears below this fraction of its thresholds (the firmware's contact
/// band: 0.9).
inline constexpr double kClearFraction = 0.9;
/// The loop alarm clears only after force and rate stayed below their clear levels this long.
inline constexpr double kLoopClearHold_s = 0.5;

/// A threshold that is never reached (an alarm switched off).
inline constexpr double kOff = std::numeric_limits<double>::infinity();

struct ForceMonitorThresholds {
    double loop_force_N = kOff;
    double loop_rate_N_per_s = kOff;
    double warning_N = kOff;
    double critical_N = kOff;
};

/// The monitor's inputs at each box period, computed once per case.
struct ForceMonitorFeatures {
    std::vector<double> time_s;
    std::vector<double> force_N;       ///< trailing mean (NaN before the first sample)
    std::vector<double> rate_N_per_s;  ///< 0 until a full rate window exists
    std::vector<std::uint8_t> advancing;
};

ForceMonitorFeatures force_monitor_features(const CaseRun& run);

/// The loop alarm per period.
std::vector<std::uint8_t> force_monitor_loop_alarm(const ForceMonitorFeatures& f, double force_N,
                                                   double rate_N_per_s);
/// One contact alarm (up while force >= threshold, down below kClearFraction x it).
std::vector<std::uint8_t> force_monitor_level_alarm(const ForceMonitorFeatures& f,
                                                    double threshold_N);
/// The contact level per period: 2 where the critical alarm is up, else 1 where the warning
/// alarm is, else 0.
std::vector<std::uint8_t> force_monitor_contact_level(const ForceMonitorFeatures& f,
                                                      const ForceMonitorThresholds& t);

/// Reads a thresholds file (written by tune_force_monitor); a threshold given as null is off.
/// Throws ModelError naming the file and field.
ForceMonitorThresholds read_force_monitor_thresholds(const std::filesystem::path& file);

/// The tuning (README, "Tuning the force monitor"): a grid search per alarm on the development
/// cases' features and true episodes. Objective: the most episodes detected within 0.5 s
/// (pooled) with at most `max_false_per_10min` false alarms per 10 minutes (pooled); ties: fewer
/// false alarms, then the smaller median latency, then the higher threshold. Returns the file's
/// JSON (the thresholds, the objective, what they score on the set).
struct TuningCase {
    std::string name;
    ForceMonitorFeatures features;
    std::vector<Episode> loops, warnings, criticals;
};
nlohmann::ordered_json tune_force_monitor(const std::vector<TuningCase>& cases,
                                          double max_false_per_10min,
                                          const std::string& manifest_name);

}  // namespace scopekin::evaluate
