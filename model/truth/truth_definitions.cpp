#include "model/truth/truth_definitions.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

#include "model/model_error.hpp"

namespace scopekin::model::truth {
namespace {

/// For every sample i, the last sample j <= i with t_j <= t_i - window (0 while the run is
/// younger than the window: the window then starts with the run).
std::vector<std::size_t> window_starts(const std::vector<double>& t, double window_s) {
    std::vector<std::size_t> start(t.size(), 0);
    std::size_t j = 0;
    for (std::size_t i = 0; i < t.size(); ++i) {
        while (j + 1 <= i && t[j + 1] <= t[i] - window_s + 1e-9)
            ++j;
        start[i] = j;
    }
    return start;
}

void check_series(const std::vector<double>& v, std::size_t n, const std::string& what,
                  const std::string& series) {
    if (v.size() != n)
        throw ModelError(what + ": " + series + " has " + std::to_string(v.size()) +
                         " samples, time_s has " + std::to_string(n));
    for (std::size_t i = 0; i < v.size(); ++i)
        if (!std::isfinite(v[i]))
            throw ModelError(what + ": " + series + "[" + std::to_string(i) +
                             "] = " + number_text(v[i]) + " is not finite");
}

void check_time(const std::vector<double>& t, const std::string& what) {
    check_series(t, t.size(), what, "time_s");
    for (std::size_t i = 1; i < t.size(); ++i)
        if (!(t[i] > t[i - 1]))
            throw ModelError(what + ": time_s[" + std::to_string(i) + "] = " + number_text(t[i]) +
                             " is not later than time_s[" + std::to_string(i - 1) +
                             "] = " + number_text(t[i - 1]));
}

/// The knee of L over [lo, hi]: the sample k that splits it into two straight pieces [lo, k] and
/// [k, hi] with the least squared error (least squares lines; ties: the later k).
std::size_t knee(const std::vector<double>& t, const std::vector<double>& l, std::size_t lo,
                 std::size_t hi) {
    if (hi <= lo + 1) return lo;
    const std::size_t n = hi - lo + 1;
    // Prefix sums over [lo, lo + m) (times relative to t[lo] for conditioning).
    std::vector<double> st(n + 1, 0), sl(n + 1, 0), stt(n + 1, 0), sll(n + 1, 0), stl(n + 1, 0);
    for (std::size_t m = 0; m < n; ++m) {
        const double x = t[lo + m] - t[lo], y = l[lo + m];
        st[m + 1] = st[m] + x;
        sl[m + 1] = sl[m] + y;
        stt[m + 1] = stt[m] + x * x;
        sll[m + 1] = sll[m] + y * y;
        stl[m + 1] = stl[m] + x * y;
    }
    // Residual sum of squares of the least squares line through samples [a, b) (local indices).
    const auto sse = [&](std::size_t a, std::size_t b) {
        const double c = static_cast<double>(b - a);
        if (c < 3) return 0.0;
        const double x = st[b] - st[a], y = sl[b] - sl[a];
        const double sxx = stt[b] - stt[a] - x * x / c;
        const double syy = sll[b] - sll[a] - y * y / c;
        const double sxy = stl[b] - stl[a] - x * y / c;
        const double r = sxx > 0 ? syy - sxy * sxy / sxx : syy;
        return std::max(0.0, r);
    };
    std::size_t best = lo;
    double best_sse = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < n; ++k) {
        const double e = sse(0, k + 1) + sse(k, n);
        if (e <= best_sse * (1.0 + 1e-12) + 1e-12) {
            best_sse = std::min(best_sse, e);
            best = lo + k;
        }
    }
    return best;
}

}  // namespace

void RunSeries::validate(const std::string& what) const {
    check_time(time_s, what);
    check_series(insertion_mm, time_s.size(), what, "insertion_mm");
    check_series(tip_path_mm, time_s.size(), what, "tip_path_mm");
}

LoopAnalysis loop_episodes(const RunSeries& run) {
    run.validate("loop episodes");
    const std::vector<double>& t = run.time_s;
    const std::vector<double>& d = run.insertion_mm;
    const std::vector<double>& p = run.tip_path_mm;
    const std::size_t n = t.size();
    LoopAnalysis out;
    out.excess_mm.assign(n, 0.0);
    out.episode.assign(n, 0);
    out.keeps_pace.assign(n, false);
    if (n == 0) return out;

    // L = depth - tip: scope in the body that has not gone into advancing the tip.
    std::vector<double> l(n);
    for (std::size_t i = 0; i < n; ++i)
        l[i] = d[i] - p[i];
    const std::vector<std::size_t> start = window_starts(t, kPaceWindow_s);

    std::size_t anchor = 0;         // the last sample at which the tip kept pace (0: the start)
    std::size_t pace_run_from = 0;  // first sample of the current run of kept-pace samples
    bool in_pace_run = false;
    std::deque<std::size_t> minimum;  // sliding minimum of L over [start[anchor], i]
    std::size_t floor = 0;            // no episode reaches back before this sample
    bool active = false;
    double base = 0;  // L where the active episode's excess began to grow
    LoopEpisode current;
    for (std::size_t i = 0; i < n; ++i) {
        const double handle = d[i] - d[start[i]];
        const double tip = p[i] - p[start[i]];
        const bool pace = handle >= kPaceMinHandle_mm && tip >= kPaceFraction * handle;
        out.keeps_pace[i] = pace;
        if (pace) {
            anchor = i;
            if (!in_pace_run) pace_run_from = i;
            in_pace_run = true;
        } else {
            in_pace_run = false;
        }
        const std::size_t lo = std::max(start[anchor], floor);
        while (!minimum.empty() && l[minimum.back()] >= l[i])
            minimum.pop_back();
        minimum.push_back(i);
        while (minimum.front() < lo)
            minimum.pop_front();
        // In an episode the excess counts from where it began to grow, however the tip moves.
        const double excess = active ? l[i] - base : l[i] - l[minimum.front()];
        out.excess_mm[i] = excess;

        if (!active) {
            if (excess >= kLoopOnsetExcess_mm) {
                active = true;
                current = LoopEpisode{};
                current.onset = knee(t, l, std::max(lo, floor), i);
                base = l[minimum.front()];
                current.onset_s = t[current.onset];
                current.detected = i;
                current.detected_s = t[i];
                current.peak = i;
                current.peak_excess_mm = excess;
            }
            continue;
        }
        if (excess > current.peak_excess_mm) {
            current.peak = i;
            current.peak_excess_mm = excess;
        }
        std::size_t end = n;
        if (excess <= kLoopEndExcess_mm) {
            end = i;
            current.end_reason = "given_back";
        } else if (in_pace_run && t[i] - t[pace_run_from] >= kLoopEndPace_s - 1e-9) {
            end = std::max(pace_run_from, current.detected);
            current.end_reason = "tip_keeps_pace";
        }
        if (end < n) {
            current.end = end;
            current.end_s = t[end];
            out.episodes.push_back(current);
            active = false;
            floor = end;
            // The excess counts afresh from the episode's end.
            minimum.clear();
            for (std::size_t j = end; j <= i; ++j) {
                while (!minimum.empty() && l[minimum.back()] >= l[j])
                    minimum.pop_back();
                minimum.push_back(j);
            }
        }
    }
    if (active) out.episodes.push_back(current);
    for (std::size_t e = 0; e < out.episodes.size(); ++e) {
        const LoopEpisode& ep = out.episodes[e];
        const std::size_t to = ep.end ? *ep.end : n;
        for (std::size_t i = ep.onset; i < to; ++i)
            out.episode[i] = static_cast<int>(e + 1);
    }
    return out;
}

std::optional<double> loop_onset_s(const RunSeries& run) {
    const LoopAnalysis a = loop_episodes(run);
    if (a.episodes.empty()) return std::nullopt;
    return a.episodes.front().onset_s;
}

std::vector<double> advance_efficiency(const RunSeries& run) {
    run.validate("advance efficiency");
    const std::vector<std::size_t> start = window_starts(run.time_s, kEfficiencyWindow_s);
    std::vector<double> out(run.time_s.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t i = 0; i < out.size(); ++i) {
        const double handle = run.insertion_mm[i] - run.insertion_mm[start[i]];
        if (handle >= kEfficiencyMinHandle_mm)
            out[i] = (run.tip_path_mm[i] - run.tip_path_mm[start[i]]) / handle;
    }
    return out;
}

std::string loop_type(ColonRegion region, bool scope_crosses) {
    switch (region) {
        case ColonRegion::sigmoid: return scope_crosses ? "alpha" : "N";
        case ColonRegion::splenic_flexure:
        case ColonRegion::transverse:
        case ColonRegion::hepatic_flexure: return scope_crosses ? "gamma" : "transverse";
        default: return "other";
    }
}

LoopShape classify_loop(const RegionBow& at_onset, const RegionBow& at_peak, bool crosses_at_peak) {
    std::size_t grew = 0, most = 0;
    for (std::size_t r = 1; r < at_peak.size(); ++r) {
        if (at_peak[r] - at_onset[r] > at_peak[grew] - at_onset[grew]) grew = r;
        if (at_peak[r] > at_peak[most]) most = r;
    }
    const std::size_t pick = at_peak[grew] - at_onset[grew] > 0.0 ? grew : most;
    LoopShape shape;
    shape.region = kColonRegionsInOrder[pick];
    shape.type = loop_type(shape.region, crosses_at_peak);
    return shape;
}

std::vector<ForceEpisode> force_episodes(const std::vector<double>& time_s,
                                         const std::vector<double>& force_N, double threshold_N,
                                         double clear_fraction, double merge_gap_s) {
    const std::string what = "force episodes";
    check_time(time_s, what);
    check_series(force_N, time_s.size(), what, "force_N");
    if (!(threshold_N > 0) || !std::isfinite(threshold_N))
        throw ModelError(what + ": threshold " + number_text(threshold_N) +
                         " N must be positive and finite");
    if (!(clear_fraction > 0 && clear_fraction <= 1))
        throw ModelError(what + ": clear fraction " + number_text(clear_fraction) +
                         " must be in (0, 1]");
    if (!(merge_gap_s >= 0) || !std::isfinite(merge_gap_s))
        throw ModelError(what + ": merge gap " + number_text(merge_gap_s) +
                         " s must be finite and >= 0");
    for (std::size_t i = 0; i < force_N.size(); ++i)
        if (force_N[i] < 0)
            throw ModelError(what + ": force_N[" + std::to_string(i) +
                             "] = " + number_text(force_N[i]) + " is negative");
    std::vector<ForceEpisode> out;
    bool active = false;
    ForceEpisode current;
    for (std::size_t i = 0; i < force_N.size(); ++i) {
        if (!active) {
            if (force_N[i] >= threshold_N) {
                active = true;
                if (!out.empty() && time_s[i] - *out.back().end_s < merge_gap_s - 1e-9) {
                    current = out.back();  // a dip shorter than the merge gap: the same episode
                    out.pop_back();
                    current.end.reset();
                    current.end_s.reset();
                    if (force_N[i] > current.peak_N) {
                        current.peak = i;
                        current.peak_N = force_N[i];
                    }
                    continue;
                }
                current = ForceEpisode{};
                current.onset = current.peak = i;
                current.onset_s = time_s[i];
                current.peak_N = force_N[i];
            }
            continue;
        }
        if (force_N[i] > current.peak_N) {
            current.peak = i;
            current.peak_N = force_N[i];
        }
        if (force_N[i] < clear_fraction * threshold_N) {
            current.end = i;
            current.end_s = time_s[i];
            out.push_back(current);
            active = false;
        }
    }
    if (active) out.push_back(current);
    return out;
}

std::vector<int> force_levels(const std::vector<double>& time_s,
                              const std::vector<double>& force_N) {
    std::vector<int> level(time_s.size(), 0);
    const auto mark = [&](double threshold, int value) {
        for (const ForceEpisode& e : force_episodes(time_s, force_N, threshold)) {
            const std::size_t to = e.end ? *e.end : level.size();
            for (std::size_t i = e.onset; i < to; ++i)
                level[i] = std::max(level[i], value);
        }
    };
    mark(kForceWarning_N, 1);
    mark(kForceCritical_N, 2);
    return level;
}

}  // namespace scopekin::model::truth
