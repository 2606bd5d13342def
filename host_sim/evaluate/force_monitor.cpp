#include "host_sim/evaluate/force_monitor.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"

namespace scopekin::evaluate {
namespace {

using Json = nlohmann::ordered_json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Json threshold_json(double v) {
    return std::isfinite(v) ? Json(v) : Json(nullptr);
}

double read_threshold(const model::io::JsonObject& o, const char* key) {
    if (!o.has(key)) throw model::ModelError(o.field(key) + ": missing (a number, or null: off)");
    if (o.raw(key).is_null()) return kOff;
    const double v = o.number(key);
    if (!(v > 0) || !std::isfinite(v))
        throw model::ModelError(o.field(key) + ": must be a positive number (or null: off)");
    return v;
}

/// Pooled score of one alarm over the tuning cases.
struct Pooled {
    std::size_t episodes = 0, detected = 0, false_alarms = 0;
    double duration_s = 0;
    std::vector<double> latencies;
    [[nodiscard]] double false_per_10min() const {
        return duration_s > 0 ? static_cast<double>(false_alarms) * 600.0 / duration_s : kNaN;
    }
    void add(const AlarmScore& s) {
        episodes += s.episodes;
        detected += s.detected;
        false_alarms += s.false_alarms;
        duration_s += s.duration_s;
        for (std::size_t i = 0; i < s.latency_s.size(); ++i)
            if (std::isfinite(s.latency_s[i]) && s.latency_s[i] <= AlarmRule{}.within_s)
                latencies.push_back(s.latency_s[i]);
    }
    [[nodiscard]] Json to_json() const {
        const double median = quantile(latencies, 0.5);
        return Json{{"episodes", episodes},
                    {"detected_within_0_5_s", detected},
                    {"false_alarms", false_alarms},
                    {"scored_s", duration_s},
                    {"false_alarms_per_10min", threshold_json(false_per_10min())},
                    {"median_latency_s", threshold_json(median)}};
    }
};

/// Better candidate first: feasible, more detections, fewer false alarms, smaller latency,
/// higher thresholds.
struct Candidate {
    double a = kOff, b = kOff;
    Pooled score;
};

bool better(const Candidate& x, const Candidate& y, double max_false) {
    const bool fx = !(x.score.false_per_10min() > max_false);
    const bool fy = !(y.score.false_per_10min() > max_false);
    if (fx != fy) return fx;
    if (!fx) {
        if (x.score.false_alarms != y.score.false_alarms)
            return x.score.false_alarms < y.score.false_alarms;
    }
    if (x.score.detected != y.score.detected) return x.score.detected > y.score.detected;
    if (x.score.false_alarms != y.score.false_alarms)
        return x.score.false_alarms < y.score.false_alarms;
    const double lx = quantile(x.score.latencies, 0.5), ly = quantile(y.score.latencies, 0.5);
    if (std::isfinite(lx) && std::isfinite(ly) && lx != ly) return lx < ly;
    if (x.a != y.a) return x.a > y.a;
    return x.b > y.b;
}

std::vector<double> grid(double from, double to, double step) {
    std::vector<double> g;
    for (double v = from; v <= to + 1e-9; v += step)
        g.push_back(v);
    return g;
}

}  // namespace

ForceMonitorFeatures force_monitor_features(const CaseRun& run) {
    ForceMonitorFeatures f;
    const std::size_t n = run.time_s.size();
    f.time_s = run.time_s;
    f.force_N.assign(n, kNaN);
    f.rate_N_per_s.assign(n, 0.0);
    f.advancing.assign(n, 0);
    // Trailing mean over (t - kForceWindow_s, t] of the 1 kHz samples.
    std::size_t first = 0, last = 0;  // samples [first, last) are in the window
    double sum = 0;
    std::size_t count = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const double t = run.time_s[k];
        while (last < run.sample_time_s.size() && run.sample_time_s[last] <= t + 1e-9) {
            if (std::isfinite(run.sample_force_N[last])) {
                sum += run.sample_force_N[last];
                ++count;
            }
            ++last;
        }
        while (first < last && run.sample_time_s[first] <= t - kForceWindow_s + 1e-9) {
            if (std::isfinite(run.sample_force_N[first])) {
                sum -= run.sample_force_N[first];
                --count;
            }
            ++first;
        }
        if (count > 0)
            f.force_N[k] = sum / static_cast<double>(count);
        else if (k > 0)
            f.force_N[k] = f.force_N[k - 1];  // no sample in the window: hold
    }
    // Rate and advance over their trailing windows (periods are in time order).
    std::size_t r = 0, a = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const double t = run.time_s[k];
        while (r + 1 < k && run.time_s[r + 1] <= t - kRateWindow_s + 1e-9)
            ++r;
        while (a + 1 < k && run.time_s[a + 1] <= t - kAdvanceWindow_s + 1e-9)
            ++a;
        if (k > 0 && run.time_s[r] <= t - kRateWindow_s + 1e-9 && std::isfinite(f.force_N[k]) &&
            std::isfinite(f.force_N[r]))
            f.rate_N_per_s[k] = (f.force_N[k] - f.force_N[r]) / (t - run.time_s[r]);
        if (k > 0 && k < run.handle_insertion_mm.size() &&
            run.time_s[a] <= t - kAdvanceWindow_s + 1e-9) {
            const double advance = run.handle_insertion_mm[k] - run.handle_insertion_mm[a];
            f.advancing[k] = advance >= kAdvanceMin_mm ? 1 : 0;
        }
    }
    return f;
}

std::vector<std::uint8_t> force_monitor_loop_alarm(const ForceMonitorFeatures& f, double force_N,
                                                   double rate_N_per_s) {
    std::vector<std::uint8_t> up(f.time_s.size(), 0);
    bool on = false;
    double calm_s = 0;
    for (std::size_t k = 0; k < f.time_s.size(); ++k) {
        const double F = f.force_N[k];
        const double R = f.rate_N_per_s[k];
        if (!on) {
            on = f.advancing[k] != 0 && (F >= force_N || R >= rate_N_per_s);
            calm_s = 0;
        } else {
            const bool calm =
                !(F >= kClearFraction * force_N) && !(R >= kClearFraction * rate_N_per_s);
            calm_s = calm ? calm_s + kPeriod_s : 0.0;
            if (calm_s >= kLoopClearHold_s - 1e-9) on = false;
        }
        up[k] = on ? 1 : 0;
    }
    return up;
}

std::vector<std::uint8_t> force_monitor_level_alarm(const ForceMonitorFeatures& f,
                                                    double threshold_N) {
    std::vector<std::uint8_t> up(f.time_s.size(), 0);
    bool on = false;
    for (std::size_t k = 0; k < f.time_s.size(); ++k) {
        const double F = f.force_N[k];
        on = on ? F >= kClearFraction * threshold_N : F >= threshold_N;
        up[k] = on ? 1 : 0;
    }
    return up;
}

std::vector<std::uint8_t> force_monitor_contact_level(const ForceMonitorFeatures& f,
                                                      const ForceMonitorThresholds& t) {
    const std::vector<std::uint8_t> warning = force_monitor_level_alarm(f, t.warning_N);
    const std::vector<std::uint8_t> critical = force_monitor_level_alarm(f, t.critical_N);
    std::vector<std::uint8_t> level(f.time_s.size(), 0);
    for (std::size_t k = 0; k < level.size(); ++k)
        level[k] = critical[k] != 0 ? 2 : (warning[k] != 0 ? 1 : 0);
    return level;
}

ForceMonitorThresholds read_force_monitor_thresholds(const std::filesystem::path& file) {
    const nlohmann::json document = model::io::parse_json_file(file.string());
    const model::io::JsonObject root(document, file.string() + ":");
    root.allow_only({"description", "tuned_on", "objective", "max_false_alarms_per_10min", "grid",
                     "loop", "warning", "critical", "command"});
    ForceMonitorThresholds t;
    const model::io::JsonObject loop = root.object("loop");
    loop.allow_only({"force_N", "rate_N_per_s", "score"});
    t.loop_force_N = read_threshold(loop, "force_N");
    t.loop_rate_N_per_s = read_threshold(loop, "rate_N_per_s");
    const model::io::JsonObject warning = root.object("warning");
    warning.allow_only({"force_N", "score"});
    t.warning_N = read_threshold(warning, "force_N");
    const model::io::JsonObject critical = root.object("critical");
    critical.allow_only({"force_N", "score"});
    t.critical_N = read_threshold(critical, "force_N");
    return t;
}

Json tune_force_monitor(const std::vector<TuningCase>& cases, double max_false_per_10min,
                        const std::string& manifest_name) {
    const std::vector<double> loop_forces = [] {
        std::vector<double> g = grid(3, 40, 1);
        g.push_back(kOff);
        return g;
    }();
    const std::vector<double> loop_rates = {1,  2,  3,  4,  5,  6,  8,  10,
                                            12, 15, 20, 25, 30, 40, 60, kOff};
    const std::vector<double> levels = grid(1, 60, 0.5);

    auto score_loop = [&](double fN, double rate) {
        Candidate c{fN, rate, {}};
        for (const TuningCase& tc : cases)
            c.score.add(score_alarm(tc.features.time_s,
                                    force_monitor_loop_alarm(tc.features, fN, rate), tc.loops,
                                    kPeriod_s));
        return c;
    };
    auto score_level = [&](double th, bool critical) {
        Candidate c{th, 0, {}};
        for (const TuningCase& tc : cases)
            c.score.add(score_alarm(tc.features.time_s, force_monitor_level_alarm(tc.features, th),
                                    critical ? tc.criticals : tc.warnings, kPeriod_s));
        return c;
    };
    std::optional<Candidate> loop;
    for (double fN : loop_forces)
        for (double rate : loop_rates) {
            Candidate c = score_loop(fN, rate);
            if (!loop || better(c, *loop, max_false_per_10min)) loop = std::move(c);
        }
    std::optional<Candidate> warning, critical;
    for (double th : levels) {
        Candidate w = score_level(th, false);
        if (!warning || better(w, *warning, max_false_per_10min)) warning = std::move(w);
    }
    for (double th : levels) {
        if (th < warning->a) continue;  // a critical level at or above the warning
        Candidate c = score_level(th, true);
        if (!critical || better(c, *critical, max_false_per_10min)) critical = std::move(c);
    }
    if (!critical) critical = score_level(warning->a, true);

    std::size_t loops = 0, warnings = 0, criticals = 0;
    for (const TuningCase& tc : cases) {
        loops += tc.loops.size();
        warnings += tc.warnings.size();
        criticals += tc.criticals.size();
    }
    Json cases_json = Json::array();
    for (const TuningCase& tc : cases)
        cases_json.push_back(tc.name);
    Json out;
    out["description"] =
        "Thresholds of the handle force monitor baseline (host_sim/evaluate/force_monitor.hpp, "
        "host_sim/evaluate/README.md): tuned by `scopekin evaluate-tune` on an evaluated "
        "development set; `scopekin evaluate` reads them.";
    out["tuned_on"] = {{"manifest", manifest_name},
                       {"cases", cases_json},
                       {"loop_episodes", loops},
                       {"warning_episodes", warnings},
                       {"critical_episodes", criticals}};
    out["objective"] =
        "per alarm: the most true episodes detected within 0.5 s (pooled over the cases) with "
        "at most max_false_alarms_per_10min false alarms per 10 minutes (pooled); ties: fewer "
        "false alarms, then the smaller median latency, then the higher threshold";
    out["max_false_alarms_per_10min"] = max_false_per_10min;
    out["grid"] = {{"loop_force_N", "3 .. 40 step 1, and off"},
                   {"loop_rate_N_per_s", "1 2 3 4 5 6 8 10 12 15 20 25 30 40 60, and off"},
                   {"contact_force_N", "1 .. 60 step 0.5 (critical >= warning)"}};
    out["loop"] = {{"force_N", threshold_json(loop->a)},
                   {"rate_N_per_s", threshold_json(loop->b)},
                   {"score", loop->score.to_json()}};
    out["warning"] = {{"force_N", threshold_json(warning->a)}, {"score", warning->score.to_json()}};
    out["critical"] = {{"force_N", threshold_json(critical->a)},
                       {"score", critical->score.to_json()}};
    return out;
}

}  // namespace scopekin::evaluate
