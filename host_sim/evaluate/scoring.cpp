#include "host_sim/evaluate/scoring.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace scopekin::evaluate {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Times are whole microseconds (the periods' release times): a difference of two is rounded to
/// the microsecond, so a lingering alarm that clears at the episode's end counts 0, not 3e-15.
double microseconds(double seconds) {
    return std::round(seconds * 1e6) / 1e6;
}

void check_times(const std::vector<double>& time_s) {
    for (std::size_t k = 0; k < time_s.size(); ++k) {
        if (!std::isfinite(time_s[k]))
            throw std::invalid_argument("time_s[" + std::to_string(k) + "] is not finite");
        if (k > 0 && !(time_s[k] > time_s[k - 1]))
            throw std::invalid_argument("time_s[" + std::to_string(k) +
                                        "] is not later than the period before");
    }
}

double median_of(std::vector<double> values) {
    return quantile(std::move(values), 0.5);
}

}  // namespace

ErrorScore score_error(const std::vector<double>& time_s, const std::vector<double>& estimate,
                       const std::vector<double>& truth) {
    if (estimate.size() != time_s.size() || truth.size() != time_s.size())
        throw std::invalid_argument("score_error: " + std::to_string(time_s.size()) + " periods, " +
                                    std::to_string(estimate.size()) + " estimates, " +
                                    std::to_string(truth.size()) + " true values");
    ErrorScore s;
    double sum = 0;
    double largest = -1;
    for (std::size_t k = 0; k < time_s.size(); ++k) {
        if (!std::isfinite(estimate[k]) || !std::isfinite(truth[k])) continue;
        const double e = estimate[k] - truth[k];
        sum += e * e;
        ++s.periods;
        if (std::abs(e) > largest) {
            largest = std::abs(e);
            s.max_time_s = time_s[k];
        }
    }
    s.rms = s.periods > 0 ? std::sqrt(sum / static_cast<double>(s.periods)) : kNaN;
    s.max = s.periods > 0 ? largest : kNaN;
    return s;
}

std::vector<double> alarm_rises(const std::vector<double>& time_s,
                                const std::vector<std::uint8_t>& up) {
    std::vector<double> rises;
    for (std::size_t k = 0; k < up.size() && k < time_s.size(); ++k)
        if (up[k] != 0 && (k == 0 || up[k - 1] == 0)) rises.push_back(time_s[k]);
    return rises;
}

double AlarmScore::detected_share() const {
    return episodes > 0 ? static_cast<double>(detected) / static_cast<double>(episodes) : kNaN;
}

double AlarmScore::false_alarms_per_10min() const {
    return duration_s > 0 ? static_cast<double>(false_alarms) * 600.0 / duration_s : kNaN;
}

double AlarmScore::median_latency_s() const {
    return median_of(latency_s);
}

double AlarmScore::median_linger_s() const {
    return median_of(linger_s);
}

AlarmScore score_alarm(const std::vector<double>& time_s, const std::vector<std::uint8_t>& up,
                       const std::vector<Episode>& episodes, double period_s,
                       const AlarmRule& rule) {
    if (up.size() != time_s.size())
        throw std::invalid_argument("score_alarm: " + std::to_string(time_s.size()) + " periods, " +
                                    std::to_string(up.size()) + " alarm states");
    if (!(rule.early_s >= 0) || !(rule.within_s >= 0) || !std::isfinite(rule.early_s) ||
        !std::isfinite(rule.within_s))
        throw std::invalid_argument("score_alarm: the rule's windows must be finite and >= 0");
    if (!(period_s > 0) || !std::isfinite(period_s))
        throw std::invalid_argument("score_alarm: the period must be positive and finite");
    check_times(time_s);
    for (std::size_t i = 0; i < episodes.size(); ++i) {
        const Episode& e = episodes[i];
        if (!std::isfinite(e.onset_s) || (e.end_s && !(*e.end_s >= e.onset_s)))
            throw std::invalid_argument("score_alarm: episode " + std::to_string(i) +
                                        " has a non-finite onset or ends before it");
        if (i > 0 && e.onset_s < episodes[i - 1].onset_s)
            throw std::invalid_argument("score_alarm: episodes are not sorted by onset");
    }
    AlarmScore s;
    s.episodes = episodes.size();
    if (time_s.empty()) {
        s.missed = episodes.size();
        s.latency_s.assign(episodes.size(), kNaN);
        return s;
    }
    const double run_end = time_s.back() + period_s;
    s.duration_s = run_end - time_s.front();
    for (std::size_t k = 0; k < up.size(); ++k)
        if (up[k] != 0) s.alarm_up_s += period_s;

    const std::vector<double> rises = alarm_rises(time_s, up);
    std::vector<bool> used(rises.size(), false);
    std::vector<bool> inside_span(rises.size(), false);
    for (const Episode& e : episodes) {
        const double from = e.onset_s - rule.early_s;
        const double to = e.end_s ? *e.end_s : run_end;
        for (std::size_t r = 0; r < rises.size(); ++r)
            if (rises[r] >= from && rises[r] <= std::max(to, e.onset_s + rule.within_s))
                inside_span[r] = true;
        // The earliest unused rise in the detection window, else the earliest unused one later
        // in the episode.
        std::optional<std::size_t> hit;
        bool timely = false;
        for (std::size_t r = 0; r < rises.size() && !hit; ++r)
            if (!used[r] && rises[r] >= from && rises[r] <= e.onset_s + rule.within_s) {
                hit = r;
                timely = true;
            }
        for (std::size_t r = 0; r < rises.size() && !hit; ++r)
            if (!used[r] && rises[r] > e.onset_s + rule.within_s && rises[r] <= to) hit = r;
        if (!hit) {
            ++s.missed;
            s.latency_s.push_back(kNaN);
            continue;
        }
        used[*hit] = true;
        (timely ? s.detected : s.late) += 1;
        s.latency_s.push_back(microseconds(std::max(0.0, rises[*hit] - e.onset_s)));
        if (e.end_s) {
            double linger = run_end - *e.end_s;
            for (std::size_t k = 0; k < time_s.size(); ++k)
                if (time_s[k] >= *e.end_s && up[k] == 0) {
                    linger = time_s[k] - *e.end_s;
                    break;
                }
            s.linger_s.push_back(microseconds(std::max(0.0, linger)));
        }
    }
    for (std::size_t r = 0; r < rises.size(); ++r)
        if (!inside_span[r]) ++s.false_alarms;
    return s;
}

double flag_share(const std::vector<std::uint32_t>& flags, unsigned bit) {
    if (flags.empty() || bit >= 32) return kNaN;
    std::size_t set = 0;
    for (const std::uint32_t f : flags)
        if ((f >> bit) & 1U) ++set;
    return static_cast<double>(set) / static_cast<double>(flags.size());
}

double quantile(std::vector<double> values, double q) {
    values.erase(
        std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
        values.end());
    if (values.empty()) return kNaN;
    std::sort(values.begin(), values.end());
    const double position = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
    const auto below = static_cast<std::size_t>(std::floor(position));
    const std::size_t above = std::min(below + 1, values.size() - 1);
    const double fraction = position - static_cast<double>(below);
    return values[below] + fraction * (values[above] - values[below]);
}

Distribution distribution(std::vector<double> values) {
    values.erase(
        std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
        values.end());
    Distribution d;
    d.count = values.size();
    if (values.empty()) {
        d.median = d.p90 = d.min = d.max = kNaN;
        return d;
    }
    d.median = quantile(values, 0.5);
    d.p90 = quantile(values, 0.9);
    d.min = *std::min_element(values.begin(), values.end());
    d.max = *std::max_element(values.begin(), values.end());
    return d;
}

}  // namespace scopekin::evaluate
