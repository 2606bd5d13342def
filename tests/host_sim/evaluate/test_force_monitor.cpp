// The handle force monitor baseline (host_sim/evaluate/force_monitor.hpp) on synthetic handle
// signals: its features (trailing mean, rate, advancing) against the closed forms of constant
// and linear signals, its alarms' thresholds and hysteresis, and the tuning's choice on a set
// whose answer is known.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "host_sim/evaluate/force_monitor.hpp"

namespace scopekin::evaluate {
namespace {

/// A run of `end_s` seconds: handle samples every 1 ms (force(t), insertion(t)), box periods
/// every 5 ms.
CaseRun synthetic(double end_s, const std::function<double(double)>& force,
                  const std::function<double(double)>& insertion) {
    CaseRun run;
    run.status = "complete";
    for (int ms = 0; ms <= static_cast<int>(std::lround(end_s * 1000)); ++ms) {
        const double t = ms * 1e-3;
        run.sample_time_s.push_back(t);
        run.sample_force_N.push_back(force(t));
        run.sample_insertion_mm.push_back(insertion(t));
    }
    for (int k = 0; k * 0.005 < end_s - 1e-12; ++k) {
        const double t = k * 0.005;
        run.time_s.push_back(t);
        run.handle_force_N.push_back(force(t));
        run.handle_insertion_mm.push_back(insertion(t));
    }
    return run;
}

double advancing_20(double t) {
    return 20.0 + 20.0 * t;
}
double holding(double) {
    return 300.0;
}

std::size_t at(const ForceMonitorFeatures&, double t) {
    return static_cast<std::size_t>(std::lround(t / 0.005));
}

TEST(ForceMonitor, FeaturesOfConstantAndLinearSignals) {
    const ForceMonitorFeatures c = force_monitor_features(synthetic(
        2.0, [](double) { return 5.0; }, advancing_20));
    EXPECT_NEAR(c.force_N[at(c, 1.0)], 5.0, 1e-12);
    EXPECT_NEAR(c.rate_N_per_s[at(c, 1.0)], 0.0, 1e-12);
    EXPECT_EQ(c.advancing[at(c, 1.0)], 1);  // 10 mm in 0.5 s
    EXPECT_EQ(c.advancing[at(c, 0.2)], 0);  // no full 0.5 s window yet
    // A ramp of 4 N/s: the 50 ms trailing mean lags by 24.5 ms (the mean of 0..49 ms), its
    // change over 0.25 s is exactly 1 N: rate 4 N/s.
    const ForceMonitorFeatures r = force_monitor_features(synthetic(
        2.0, [](double t) { return 4.0 * t; }, holding));
    EXPECT_NEAR(r.force_N[at(r, 1.0)], 4.0 * (1.0 - 0.0245), 1e-9);
    EXPECT_NEAR(r.rate_N_per_s[at(r, 1.0)], 4.0, 1e-9);
    EXPECT_EQ(r.advancing[at(r, 1.0)], 0);  // the hand holds
}

TEST(ForceMonitor, LoopAlarmNeedsTheHandToAdvanceAndClearsAfterTheHold) {
    // 12 N from 1 s to 2 s, 2 N otherwise.
    auto force = [](double t) { return t >= 1.0 && t < 2.0 ? 12.0 : 2.0; };
    const ForceMonitorFeatures pushing =
        force_monitor_features(synthetic(4.0, force, advancing_20));
    const auto up = force_monitor_loop_alarm(pushing, 10.0, kOff);
    EXPECT_EQ(up[at(pushing, 0.9)], 0);
    // The 50 ms mean reaches 10 N once 41 of its 50 samples are at 12 N: 1.040 s.
    EXPECT_EQ(up[at(pushing, 1.035)], 0);
    EXPECT_EQ(up[at(pushing, 1.045)], 1);
    // The mean falls below 9 N (0.9 x 10 N) once 16 samples are at 2 N (2.015 s); the alarm
    // clears 0.5 s later.
    EXPECT_EQ(up[at(pushing, 2.5)], 1);
    EXPECT_EQ(up[at(pushing, 2.6)], 0);
    const ForceMonitorFeatures still = force_monitor_features(synthetic(4.0, force, holding));
    for (std::uint8_t a : force_monitor_loop_alarm(still, 10.0, kOff))
        EXPECT_EQ(a, 0);  // the same force while the hand holds: no loop alarm
    // The rate alone: a 10 N step over 50 ms reaches 20 N/s within the 0.25 s window.
    const auto by_rate = force_monitor_loop_alarm(pushing, kOff, 20.0);
    EXPECT_EQ(by_rate[at(pushing, 1.1)], 1);
}

TEST(ForceMonitor, ContactLevelsWithHysteresis) {
    // 11 N from 1 s, 9.5 N from 2 s (still >= 0.9 x 10 N), 8.5 N from 3 s; 15 N at 4-4.5 s.
    auto force = [](double t) {
        if (t >= 4.0 && t < 4.5) return 15.0;
        if (t >= 3.0) return 8.5;
        if (t >= 2.0) return 9.5;
        if (t >= 1.0) return 11.0;
        return 0.0;
    };
    const ForceMonitorFeatures f = force_monitor_features(synthetic(5.0, force, holding));
    const auto level = force_monitor_contact_level(f, {kOff, kOff, 10.0, 14.0});
    EXPECT_EQ(level[at(f, 0.5)], 0);
    EXPECT_EQ(level[at(f, 1.5)], 1);
    EXPECT_EQ(level[at(f, 2.5)], 1);  // 9.5 N >= 9 N: still up
    EXPECT_EQ(level[at(f, 3.5)], 0);
    EXPECT_EQ(level[at(f, 4.2)], 2);
    EXPECT_EQ(level[at(f, 4.8)], 0);
}

TEST(ForceMonitor, TuningFindsThresholdsThatDetectTheEpisodesWithoutFalseAlarms) {
    // While advancing: a 12 N push during a true loop and contact episode (3-5 s), and a 6 N
    // bump without one (7-7.5 s): a warning threshold in (6, 12] N detects the episode without
    // a false alarm, and so does a loop alarm that ignores the bump.
    auto force = [](double t) {
        if (t >= 3.0 && t < 5.0) return 12.0;
        if (t >= 7.0 && t < 7.5) return 6.0;
        return 2.0;
    };
    TuningCase c;
    c.name = "synthetic";
    c.features = force_monitor_features(synthetic(10.0, force, advancing_20));
    c.loops = {{3.0, 5.0, "", std::nullopt}};
    c.warnings = {{3.0, 5.0, "", std::nullopt}};
    const auto tuned = tune_force_monitor({c}, 0.0, "development");
    const double loop_force =
        tuned["loop"]["force_N"].is_null() ? kOff : tuned["loop"]["force_N"].get<double>();
    const double loop_rate = tuned["loop"]["rate_N_per_s"].is_null()
                                 ? kOff
                                 : tuned["loop"]["rate_N_per_s"].get<double>();
    const AlarmScore loop =
        score_alarm(c.features.time_s, force_monitor_loop_alarm(c.features, loop_force, loop_rate),
                    c.loops, kPeriod_s);
    EXPECT_EQ(loop.detected, 1U);
    EXPECT_EQ(loop.false_alarms, 0U);
    EXPECT_EQ(tuned["loop"]["score"]["detected_within_0_5_s"], 1);
    const double warning = tuned["warning"]["force_N"].get<double>();
    EXPECT_GT(warning, 6.0);
    EXPECT_LE(warning, 12.0);
    EXPECT_EQ(tuned["warning"]["score"]["false_alarms"], 0);
    EXPECT_EQ(tuned["tuned_on"]["manifest"], "development");
    // No critical episode: nothing to detect, so the highest threshold (fewest false alarms).
    EXPECT_EQ(tuned["critical"]["score"]["episodes"], 0);
    EXPECT_DOUBLE_EQ(tuned["critical"]["force_N"].get<double>(), 60.0);
}

}  // namespace
}  // namespace scopekin::evaluate
