#pragma once
// Scoring an estimator's outputs against the ground truth (host_sim/evaluate/README.md, "The
// scoring rules"): pure functions over series sampled at the box's periods, no world, no files.
//
// Units: s, mm, N. Series are aligned: element k of every series belongs to period k, whose
// release time is time_s[k] (strictly increasing). A NaN in a truth or estimate series leaves
// that period out of an error measure.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace scopekin::evaluate {

/// A true episode (a loop, or a contact force at or above a threshold): from its onset to its
/// end; no end = still up when the run ended.
struct Episode {
    double onset_s = 0;
    std::optional<double> end_s;
    std::string label;  ///< loop: "N sigmoid"; force: "" (for reports only)
    /// When the definition's own threshold was reached (loop: the excess at 20 mm, summary.json
    /// "detected_s"); absent where it is the onset (force episodes: the force crossing the level).
    std::optional<double> confirmed_s;
};

/// An error measure over the periods where both series are defined.
struct ErrorScore {
    std::size_t periods = 0;  ///< periods scored (0: NaN measures)
    double rms = 0;           ///< sqrt(mean((estimate - truth)^2)), NaN without periods
    double max = 0;           ///< max |estimate - truth|, NaN without periods
    double max_time_s = 0;    ///< when the largest error occurred
};

/// RMS and largest absolute error of `estimate` against `truth` (same length as `time_s`;
/// throws std::invalid_argument otherwise).
ErrorScore score_error(const std::vector<double>& time_s, const std::vector<double>& estimate,
                       const std::vector<double>& truth);

/// The detection rule (README, "Alarms against episodes"). An alarm rise (a period with the alarm
/// up after one with it down; or the first period if the alarm is up there) at time r
/// detects the episode with onset o when o - early_s <= r <= o + within_s; the latency is
/// max(0, r - o). A first rise in (o + within_s, end] is a late detection. A rise inside
/// [o - early_s, end] of any episode (end: the run's end if none) is not a false alarm; every other
/// rise is one. After an episode that ended, the alarm lingers from the end to the first period
/// with the alarm down at or after it (the run's end if it never comes down).
struct AlarmRule {
    double early_s = 1.0;   ///< a rise this long before the onset still detects it (README)
    double within_s = 0.5;  ///< ... and this long after it
};

struct AlarmScore {
    std::size_t episodes = 0;
    std::size_t detected = 0;  ///< a rise within [onset - early_s, onset + within_s]
    std::size_t late = 0;      ///< the first rise after onset + within_s, before the end
    std::size_t missed = 0;    ///< episodes - detected - late: no rise from onset - early_s to end
    std::size_t false_alarms = 0;
    double duration_s = 0;  ///< the scored time: last period - first period + one period
    /// Per episode (in order): the latency of the detection or late detection [s]; NaN if missed.
    std::vector<double> latency_s;
    /// Per episode that ended and was detected (or late): how long the alarm stayed up after
    /// the end [s].
    std::vector<double> linger_s;
    double alarm_up_s = 0;  ///< total time with the alarm up

    /// detected / episodes; NaN without episodes.
    [[nodiscard]] double detected_share() const;
    /// false_alarms per 10 minutes of scored time; NaN without time.
    [[nodiscard]] double false_alarms_per_10min() const;
    /// Median of the finite latencies (NaN if none).
    [[nodiscard]] double median_latency_s() const;
    /// Median of linger_s (NaN if none).
    [[nodiscard]] double median_linger_s() const;
};

/// Scores an alarm (up[k] != 0: raised in period k) against the true episodes (sorted by
/// onset). `period_s` is the box's period (the scored duration counts the last period whole).
/// Throws std::invalid_argument for series of different lengths, time not increasing, a
/// non-finite time or onset, an end before its onset, or a rule with a negative window.
AlarmScore score_alarm(const std::vector<double>& time_s, const std::vector<std::uint8_t>& up,
                       const std::vector<Episode>& episodes, double period_s,
                       const AlarmRule& rule = {});

/// Rising edges of an alarm: the times of periods with the alarm up after one with it down (the
/// first period counts if it is up).
std::vector<double> alarm_rises(const std::vector<double>& time_s,
                                const std::vector<std::uint8_t>& up);

/// Share of periods (0..1) with `bit` set in `flags`; NaN for no periods.
double flag_share(const std::vector<std::uint32_t>& flags, unsigned bit);

/// Order statistics over the finite values of a measure (NaN if none): the median, the 90th
/// percentile (linear interpolation between order statistics, as numpy's default), the
/// smallest and the largest.
struct Distribution {
    std::size_t count = 0;
    double median = 0, p90 = 0, min = 0, max = 0;
};
Distribution distribution(std::vector<double> values);

/// The q-quantile (0..1) of finite values, linear between order statistics; NaN if none.
double quantile(std::vector<double> values, double q);

}  // namespace scopekin::evaluate
