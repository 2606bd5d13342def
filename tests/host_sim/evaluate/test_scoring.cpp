// The scoring rules (host_sim/evaluate/scoring.hpp) on synthetic traces whose answers are worked
// out by hand: errors, alarm detection within the window, late and missed episodes, false
// alarms per 10 minutes, the time an alarm lingers, order statistics.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "host_sim/evaluate/scoring.hpp"

namespace scopekin::evaluate {
namespace {

constexpr double kPeriod = 0.005;

/// Period times 0, 0.005, ... up to (not including) `end_s`.
std::vector<double> periods(double end_s) {
    std::vector<double> t;
    for (int k = 0; k * kPeriod < end_s - 1e-12; ++k)
        t.push_back(k * kPeriod);
    return t;
}

/// The alarm up over each [from, to) interval.
std::vector<std::uint8_t> alarm(const std::vector<double>& t,
                                const std::vector<std::pair<double, double>>& up) {
    std::vector<std::uint8_t> a(t.size(), 0);
    for (std::size_t k = 0; k < t.size(); ++k)
        for (const auto& [from, to] : up)
            if (t[k] >= from - 1e-9 && t[k] < to - 1e-9) a[k] = 1;
    return a;
}

TEST(Scoring, ErrorIsTheRmsAndTheLargestOfTheDefinedPeriods) {
    const std::vector<double> t{0.0, 0.005, 0.010, 0.015};
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const std::vector<double> truth{100, 100, 100, nan};
    const std::vector<double> estimate{103, 96, nan, 500};
    const ErrorScore e = score_error(t, estimate, truth);
    EXPECT_EQ(e.periods, 2U);
    EXPECT_NEAR(e.rms, std::sqrt((9.0 + 16.0) / 2.0), 1e-12);
    EXPECT_DOUBLE_EQ(e.max, 4.0);
    EXPECT_DOUBLE_EQ(e.max_time_s, 0.005);
    EXPECT_TRUE(std::isnan(score_error(t, {nan, nan, nan, nan}, truth).rms));
    EXPECT_THROW(score_error(t, {1.0}, truth), std::invalid_argument);
}

TEST(Scoring, ARiseWithinHalfASecondDetectsWithItsLatencyAndTheLingerAfterTheEnd) {
    const auto t = periods(10.0);
    const std::vector<Episode> episodes{{2.0, 4.0, "", std::nullopt}};
    const AlarmScore s = score_alarm(t, alarm(t, {{2.3, 4.5}}), episodes, kPeriod);
    EXPECT_EQ(s.episodes, 1U);
    EXPECT_EQ(s.detected, 1U);
    EXPECT_EQ(s.late + s.missed + s.false_alarms, 0U);
    ASSERT_EQ(s.latency_s.size(), 1U);
    EXPECT_NEAR(s.latency_s[0], 0.3, 1e-9);
    ASSERT_EQ(s.linger_s.size(), 1U);
    EXPECT_NEAR(s.linger_s[0], 0.5, 1e-9);  // up until 4.5 s, the episode ended at 4.0 s
    EXPECT_NEAR(s.duration_s, 10.0, 1e-9);
    EXPECT_NEAR(s.alarm_up_s, 2.2, 1e-6);
    EXPECT_DOUBLE_EQ(s.detected_share(), 1.0);
    EXPECT_DOUBLE_EQ(s.false_alarms_per_10min(), 0.0);
}

TEST(Scoring, ARiseUpToOneSecondEarlyDetectsWithLatencyZero) {
    const auto t = periods(10.0);
    const AlarmScore s =
        score_alarm(t, alarm(t, {{1.1, 3.0}}), {{2.0, 4.0, "", std::nullopt}}, kPeriod);
    EXPECT_EQ(s.detected, 1U);
    EXPECT_DOUBLE_EQ(s.latency_s[0], 0.0);
    EXPECT_DOUBLE_EQ(s.linger_s[0], 0.0);  // down before the end
    // 1.1 s early is outside the window: the rise is a false alarm and the episode is missed.
    const AlarmScore early =
        score_alarm(t, alarm(t, {{0.9, 6.0}}), {{2.0, 4.0, "", std::nullopt}}, kPeriod);
    EXPECT_EQ(early.detected, 0U);
    EXPECT_EQ(early.missed, 1U);
    EXPECT_EQ(early.false_alarms, 1U);
    EXPECT_TRUE(std::isnan(early.latency_s[0]));
}

TEST(Scoring, AnAlarmUpLongBeforeTheOnsetIsAFalseAlarmNotADetection) {
    const auto t = periods(10.0);
    const AlarmScore s =
        score_alarm(t, alarm(t, {{0.5, 9.0}}), {{2.0, 4.0, "", std::nullopt}}, kPeriod);
    EXPECT_EQ(s.detected, 0U);
    EXPECT_EQ(s.late, 0U);
    EXPECT_EQ(s.missed, 1U);
    EXPECT_EQ(s.false_alarms, 1U);
    EXPECT_NEAR(s.false_alarms_per_10min(), 60.0, 1e-9);  // one in 10 s
    EXPECT_TRUE(s.linger_s.empty());                      // a missed episode does not linger
    EXPECT_TRUE(std::isnan(s.median_latency_s()));
}

TEST(Scoring, ARiseLaterInTheEpisodeIsLateAndNotFalse) {
    const auto t = periods(10.0);
    const AlarmScore s =
        score_alarm(t, alarm(t, {{3.0, 3.5}}), {{2.0, 4.0, "", std::nullopt}}, kPeriod);
    EXPECT_EQ(s.detected, 0U);
    EXPECT_EQ(s.late, 1U);
    EXPECT_EQ(s.missed, 0U);
    EXPECT_EQ(s.false_alarms, 0U);
    EXPECT_NEAR(s.latency_s[0], 1.0, 1e-9);
    EXPECT_NEAR(s.median_latency_s(), 1.0, 1e-9);
}

TEST(Scoring, ChatterInsideAnEpisodeIsOneDetectionAndNoFalseAlarm) {
    const auto t = periods(10.0);
    const AlarmScore s = score_alarm(t, alarm(t, {{2.1, 2.4}, {2.6, 2.8}, {3.0, 3.9}}),
                                     {{2.0, 4.0, "", std::nullopt}}, kPeriod);
    EXPECT_EQ(alarm_rises(t, alarm(t, {{2.1, 2.4}, {2.6, 2.8}, {3.0, 3.9}})).size(), 3U);
    EXPECT_EQ(s.detected, 1U);
    EXPECT_EQ(s.false_alarms, 0U);
    EXPECT_NEAR(s.latency_s[0], 0.1, 1e-9);
}

TEST(Scoring, RisesOutsideEveryEpisodeAreFalseAlarmsPer10Minutes) {
    const auto t = periods(60.0);
    // Episodes 10-12 s (detected) and 40 s to the end (open: no end, no linger); rises at 5 s,
    // 20 s and 30 s are false: 3 in 60 s = 30 per 10 minutes.
    const std::vector<Episode> episodes{{10.0, 12.0, "", std::nullopt},
                                        {40.0, std::nullopt, "", std::nullopt}};
    const auto up = alarm(t, {{5, 6}, {10.2, 11}, {20, 21}, {30, 31}, {40.4, 60}});
    const AlarmScore s = score_alarm(t, up, episodes, kPeriod);
    EXPECT_EQ(s.episodes, 2U);
    EXPECT_EQ(s.detected, 2U);
    EXPECT_EQ(s.false_alarms, 3U);
    EXPECT_NEAR(s.false_alarms_per_10min(), 30.0, 1e-9);
    ASSERT_EQ(s.linger_s.size(), 1U);
    EXPECT_DOUBLE_EQ(s.linger_s[0], 0.0);
    EXPECT_NEAR(s.median_latency_s(), 0.3, 1e-9);  // 0.2 and 0.4
}

TEST(Scoring, AnAlarmStillUpAtTheEndLingersToTheEndOfTheRun) {
    const auto t = periods(10.0);
    const AlarmScore s =
        score_alarm(t, alarm(t, {{2.0, 10.0}}), {{2.0, 4.0, "", std::nullopt}}, kPeriod);
    ASSERT_EQ(s.linger_s.size(), 1U);
    EXPECT_NEAR(s.linger_s[0], 6.0, 1e-9);  // from 4 s to the run's end (10 s)
}

TEST(Scoring, OneRiseDetectsOneEpisodeOnly) {
    const auto t = periods(10.0);
    // Two episodes 0.3 s apart: the one rise (at 2.1 s) is in both windows; it detects the
    // first, and the second is missed.
    const AlarmScore s =
        score_alarm(t, alarm(t, {{2.1, 3.0}}),
                    {{2.0, 2.2, "", std::nullopt}, {2.3, 2.8, "", std::nullopt}}, kPeriod);
    EXPECT_EQ(s.detected, 1U);
    EXPECT_EQ(s.missed, 1U);
    EXPECT_EQ(s.false_alarms, 0U);
}

TEST(Scoring, NoEpisodesNoAlarmsGiveNaNShares) {
    const auto t = periods(1.0);
    const AlarmScore s = score_alarm(t, alarm(t, {}), {}, kPeriod);
    EXPECT_TRUE(std::isnan(s.detected_share()));
    EXPECT_DOUBLE_EQ(s.false_alarms_per_10min(), 0.0);
    const AlarmScore empty = score_alarm({}, {}, {{1.0, 2.0, "", std::nullopt}}, kPeriod);
    EXPECT_EQ(empty.missed, 1U);
}

TEST(Scoring, BadInputIsRefused) {
    const auto t = periods(1.0);
    EXPECT_THROW(score_alarm(t, std::vector<std::uint8_t>(3, 0), {}, kPeriod),
                 std::invalid_argument);
    EXPECT_THROW(score_alarm({0.0, 0.0}, {0, 0}, {}, kPeriod), std::invalid_argument);
    EXPECT_THROW(score_alarm(t, alarm(t, {}), {{0.5, 0.2, "", std::nullopt}}, kPeriod),
                 std::invalid_argument);
    EXPECT_THROW(score_alarm(t, alarm(t, {}),
                             {{0.5, 0.6, "", std::nullopt}, {0.1, 0.2, "", std::nullopt}}, kPeriod),
                 std::invalid_argument);
    EXPECT_THROW(score_alarm(t, alarm(t, {}), {}, 0.0), std::invalid_argument);
    EXPECT_THROW(score_alarm(t, alarm(t, {}), {}, kPeriod, AlarmRule{-1.0, 0.5}),
                 std::invalid_argument);
}

TEST(Scoring, QuantilesInterpolateBetweenOrderStatisticsLikeNumpy) {
    // numpy.percentile([1, 2, 3, 4], 90) = 3.7, median 2.5; NaNs are left out.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_NEAR(quantile({4, 1, nan, 3, 2}, 0.9), 3.7, 1e-12);
    EXPECT_NEAR(quantile({4, 1, 3, 2}, 0.5), 2.5, 1e-12);
    EXPECT_TRUE(std::isnan(quantile({nan}, 0.5)));
    const Distribution d = distribution({5, 1, 3});
    EXPECT_EQ(d.count, 3U);
    EXPECT_DOUBLE_EQ(d.median, 3.0);
    EXPECT_NEAR(d.p90, 4.6, 1e-12);
    EXPECT_DOUBLE_EQ(d.max, 5.0);
    EXPECT_DOUBLE_EQ(d.min, 1.0);
}

TEST(Scoring, FlagShareCountsThePeriodsWithTheBit) {
    const std::vector<std::uint32_t> flags{0, 1U << 11U, (1U << 11U) | 1U, 0};
    EXPECT_DOUBLE_EQ(flag_share(flags, 11), 0.5);
    EXPECT_DOUBLE_EQ(flag_share(flags, 0), 0.25);
    EXPECT_DOUBLE_EQ(flag_share(flags, 3), 0.0);
    EXPECT_TRUE(std::isnan(flag_share({}, 0)));
}

}  // namespace
}  // namespace scopekin::evaluate
