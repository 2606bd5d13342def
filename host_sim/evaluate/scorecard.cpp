#include "host_sim/evaluate/scorecard.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <tuple>

#include "host_sim/evaluate/scoring.hpp"
#include "host_sim/recording/recording_format.hpp"

namespace scopekin::evaluate {
namespace {

using recording::csv_cell;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The three alarms and the truth episodes each is scored against.
struct AlarmKind {
    const char* key;    ///< in the JSON
    const char* title;  ///< in the tables
};
constexpr AlarmKind kAlarms[] = {{"loop_alarm", "loop alarm"},
                                 {"warning_alarm", "contact force alarm >= 10 N"},
                                 {"critical_alarm", "contact force alarm >= 14 N"}};

Json num(double v) {
    return std::isfinite(v) ? Json(v) : Json(nullptr);
}

double get(const Json& j, const char* key) {
    return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : kNaN;
}

/// j[key], or null when j is not an object or has no such member (a const operator[] on a
/// missing key is undefined: scores written before a member existed lack it).
const Json& member(const Json& j, const char* key) {
    static const Json null_json;
    return j.is_object() && j.contains(key) ? j[key] : null_json;
}

/// How often the truth lies within the stated uncertainty: the share of periods with
/// |estimate - truth| <= 1 SD and <= 2 SD (a Gaussian error: 68 % and 95 %).
Json within_sd_json(const std::vector<double>& estimate, const std::vector<double>& sd,
                    const std::vector<double>& truth) {
    std::size_t one = 0, two = 0, periods = 0;
    for (std::size_t k = 0; k < estimate.size() && k < sd.size() && k < truth.size(); ++k) {
        const double error = std::abs(estimate[k] - truth[k]);
        if (std::isnan(error) || std::isnan(sd[k])) continue;
        ++periods;
        if (error <= sd[k]) ++one;
        if (error <= 2.0 * sd[k]) ++two;
    }
    return {{"periods", periods}, {"within_1_sd", one}, {"within_2_sd", two}};
}

/// The contact-force level against the truth's largest force period by period: the periods with
/// the truth at or above each threshold (10 N, 14 N) and those the level was up in, and the
/// periods with the truth below 90 % of it (the monitor's clear level) and those it was up in.
/// An alarm held through a long hard push is counted in every period it is right, which the
/// episodes' onsets (score_alarm) do not see.
Json level_periods_json(const std::vector<std::uint8_t>& level, const std::vector<double>& truth) {
    Json out = Json::object();
    for (const auto& [name, threshold_N, at_least] :
         {std::tuple{"warning_10N", 10.0, 1}, std::tuple{"critical_14N", 14.0, 2}}) {
        std::size_t over = 0, up_over = 0, below = 0, up_below = 0;
        for (std::size_t k = 0; k < level.size() && k < truth.size(); ++k) {
            if (std::isnan(truth[k])) continue;
            const bool up = level[k] >= at_least;
            if (truth[k] >= threshold_N) {
                ++over;
                if (up) ++up_over;
            } else if (truth[k] < 0.9 * threshold_N) {
                ++below;
                if (up) ++up_below;
            }
        }
        out[name] = {{"periods_over", over},
                     {"up_over", up_over},
                     {"periods_below", below},
                     {"up_below", up_below}};
    }
    return out;
}

Json error_json(const ErrorScore& e) {
    if (e.periods == 0) return nullptr;
    return Json{{"rms", num(e.rms)},
                {"max", num(e.max)},
                {"max_time_s", e.max_time_s},
                {"periods", e.periods}};
}

Json alarm_json(const AlarmScore& s) {
    Json latencies = Json::array(), lingers = Json::array();
    for (double v : s.latency_s)
        latencies.push_back(num(v));
    for (double v : s.linger_s)
        lingers.push_back(num(v));
    return Json{{"episodes", s.episodes},
                {"detected", s.detected},
                {"late", s.late},
                {"missed", s.missed},
                {"false_alarms", s.false_alarms},
                {"scored_s", s.duration_s},
                {"detected_share", num(s.detected_share())},
                {"false_alarms_per_10min", num(s.false_alarms_per_10min())},
                {"median_latency_s", num(s.median_latency_s())},
                {"median_linger_s", num(s.median_linger_s())},
                {"alarm_up_s", s.alarm_up_s},
                {"latency_s", latencies},
                {"linger_s", lingers}};
}

Json distribution_json(const std::vector<double>& values) {
    const Distribution d = distribution(values);
    return Json{
        {"cases", d.count}, {"median", num(d.median)}, {"p90", num(d.p90)}, {"worst", num(d.max)}};
}

std::string fmt(double v, const char* format = "%.3g") {
    if (!std::isfinite(v)) return "n/a";
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, format, v);
    return buffer;
}

/// A share as a percentage; "< 0.1 %" for a share that is not 0 but rounds to it.
std::string percent(double share) {
    if (std::isfinite(share) && share > 0 && share < 0.0005) return "< 0.1 %";
    return fmt(100.0 * share, "%.1f") + " %";
}

std::string fmt_json(const Json& j, const char* key, const char* format = "%.3g") {
    return fmt(get(j, key), format);
}

std::string csv_number(double v) {
    if (!std::isfinite(v)) return "";
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.6g", v);
    return buffer;
}

}  // namespace

Json unscored_case(const std::string& name, const std::string& style, const std::string& folder,
                   const std::string& status, const std::string& message) {
    return Json{{"case", name},     {"style", style},     {"folder", folder},
                {"status", status}, {"message", message}, {"estimators", Json::object()}};
}

Json score_case(const std::string& name, const std::string& style, const std::string& folder,
                const CaseRun& run, const std::vector<EstimatorOutput>& outputs) {
    Json s;
    s["case"] = name;
    s["style"] = style;
    s["folder"] = folder;
    s["status"] = run.status;
    s["message"] = run.message;
    s["duration_s"] = run.duration_s;
    s["wall_time_s"] = run.wall_time_s;
    s["periods"] = run.time_s.size();
    s["scope_through_wall_s"] = run.scope_through_wall_s ? Json(*run.scope_through_wall_s) : Json();
    if (run.procedure.known) {
        const ProcedureOutcome& p = run.procedure;
        s["procedure"] = {{"kind", p.kind},
                          {"style", p.style},
                          {"cecum_reached", p.cecum_reached ? Json(*p.cecum_reached) : Json()},
                          {"cecum_time_s", p.cecum_time_s ? Json(*p.cecum_time_s) : Json()},
                          {"insertion_at_cecum_mm",
                           p.insertion_at_cecum_mm ? Json(*p.insertion_at_cecum_mm) : Json()}};
    } else {
        s["procedure"] = nullptr;
    }
    s["truth"] = {{"loop_episodes", run.loop_episodes.size()},
                  {"warning_episodes", run.warning_episodes.size()},
                  {"critical_episodes", run.critical_episodes.size()}};
    Json estimators = Json::object();
    if (run.status == "complete") {
        for (std::size_t i = 0; i < estimator_registry().size() && i < outputs.size(); ++i) {
            const Estimator& e = estimator_registry()[i];
            const EstimatorOutput& o = outputs[i];
            Json j;
            j["label"] = e.label;
            j["tip_error_mm"] =
                o.tip_path_mm.empty()
                    ? Json()
                    : error_json(score_error(run.time_s, o.tip_path_mm, run.true_tip_path_mm));
            j["tip_within_sd"] =
                o.tip_uncertainty_mm.empty()
                    ? Json()
                    : within_sd_json(o.tip_path_mm, o.tip_uncertainty_mm, run.true_tip_path_mm);
            j["force_error_N"] = o.max_force_N.empty()
                                     ? Json()
                                     : error_json(score_error(run.time_s, o.max_force_N,
                                                              run.true_max_station_force_N));
            std::vector<std::uint8_t> warning(o.contact_level.size()), critical(warning.size());
            for (std::size_t k = 0; k < warning.size(); ++k) {
                warning[k] = o.contact_level[k] >= 1 ? 1 : 0;
                critical[k] = o.contact_level[k] >= 2 ? 1 : 0;
            }
            j["loop_alarm"] =
                alarm_json(score_alarm(run.time_s, o.loop_alarm, run.loop_episodes, kPeriod_s));
            j["warning_alarm"] =
                alarm_json(score_alarm(run.time_s, warning, run.warning_episodes, kPeriod_s));
            j["critical_alarm"] =
                alarm_json(score_alarm(run.time_s, critical, run.critical_episodes, kPeriod_s));
            j["contact_level_periods"] =
                o.contact_level.empty()
                    ? Json()
                    : level_periods_json(o.contact_level, run.true_max_station_force_N);
            if (o.fault_flags.empty()) {
                j["fault_share"] = nullptr;
            } else {
                Json shares = Json::object();
                const auto& names = fault_flag_names();
                for (unsigned bit = 0; bit < names.size(); ++bit)
                    shares[names[bit]] = flag_share(o.fault_flags, bit);
                j["fault_share"] = shares;
            }
            estimators[e.name] = j;
        }
    }
    s["estimators"] = estimators;
    return s;
}

std::string estimates_csv(const CaseRun& run, const std::vector<EstimatorOutput>& outputs) {
    const std::size_t n = run.time_s.size();
    auto inside = [&](const std::vector<Episode>& episodes, double t) {
        for (std::size_t i = 0; i < episodes.size(); ++i)
            if (t >= episodes[i].onset_s && (!episodes[i].end_s || t < *episodes[i].end_s))
                return true;
        return false;
    };
    std::ostringstream out;
    out << "time_s,true_tip_path_mm,true_max_station_force_N,true_loop,true_force_level";
    for (std::size_t i = 0; i < outputs.size() && i < estimator_registry().size(); ++i) {
        const std::string& name = estimator_registry()[i].name;
        out << ',' << name << "_tip_path_mm," << name << "_max_force_N," << name << "_loop_alarm,"
            << name << "_contact_level";
    }
    out << '\n';
    char buffer[32];
    for (std::size_t k = 0; k < n; ++k) {
        const double t = run.time_s[k];
        std::snprintf(buffer, sizeof buffer, "%.6f", t);
        out << buffer << ',' << csv_number(run.true_tip_path_mm[k]) << ','
            << csv_number(run.true_max_station_force_N[k]) << ','
            << (inside(run.loop_episodes, t) ? 1 : 0) << ','
            << (inside(run.critical_episodes, t) ? 2 : (inside(run.warning_episodes, t) ? 1 : 0));
        for (std::size_t i = 0; i < outputs.size() && i < estimator_registry().size(); ++i) {
            const EstimatorOutput& o = outputs[i];
            out << ',' << (k < o.tip_path_mm.size() ? csv_number(o.tip_path_mm[k]) : "") << ','
                << (k < o.max_force_N.size() ? csv_number(o.max_force_N[k]) : "") << ','
                << (k < o.loop_alarm.size() ? std::to_string(o.loop_alarm[k]) : "") << ','
                << (k < o.contact_level.size() ? std::to_string(o.contact_level[k]) : "");
        }
        out << '\n';
    }
    return out.str();
}

Json aggregate(const std::vector<Json>& cases) {
    Json overall;
    std::size_t scored = 0;
    Json not_scored = Json::array();
    double simulated_s = 0, wall_s = 0;
    for (const Json& c : cases) {
        if (c.value("status", "") == "complete") {
            ++scored;
            simulated_s += get(c, "duration_s");
            wall_s += get(c, "wall_time_s");
        } else {
            not_scored.push_back({{"case", c.value("case", "")},
                                  {"status", c.value("status", "")},
                                  {"message", c.value("message", "")}});
        }
    }
    overall["cases"] = cases.size();
    overall["scored"] = scored;
    overall["not_scored"] = not_scored;
    // Cases in which the scope went through the wall: scored only before that moment.
    Json cut_short = Json::array();
    for (const Json& c : cases)
        if (c.value("status", "") == "complete" && c.contains("scope_through_wall_s") &&
            c["scope_through_wall_s"].is_number())
            cut_short.push_back({{"case", c.value("case", "")},
                                 {"scope_through_wall_s", c["scope_through_wall_s"]},
                                 {"duration_s", c.value("duration_s", 0.0)}});
    overall["cut_short"] = cut_short;
    overall["simulated_s"] = simulated_s;
    overall["simulation_wall_s"] = wall_s;
    Json estimators = Json::array();
    for (const Estimator& e : estimator_registry()) {
        Json j;
        j["name"] = e.name;
        j["label"] = e.label;
        std::vector<double> tip_rms, tip_max, force_rms;
        for (const Json& c : cases) {
            if (!c.contains("estimators") || !c["estimators"].contains(e.name)) continue;
            const Json& s = c["estimators"][e.name];
            tip_rms.push_back(get(s["tip_error_mm"], "rms"));
            tip_max.push_back(get(s["tip_error_mm"], "max"));
            force_rms.push_back(get(s["force_error_N"], "rms"));
        }
        std::size_t sd_periods = 0, sd_one = 0, sd_two = 0;
        for (const Json& c : cases) {
            if (!c.contains("estimators") || !c["estimators"].contains(e.name)) continue;
            const Json& w = member(c["estimators"][e.name], "tip_within_sd");
            if (!w.is_object()) continue;
            sd_periods += w.value("periods", std::size_t{0});
            sd_one += w.value("within_1_sd", std::size_t{0});
            sd_two += w.value("within_2_sd", std::size_t{0});
        }
        const auto sd_share = [sd_periods](std::size_t n) {
            return num(sd_periods > 0 ? static_cast<double>(n) / static_cast<double>(sd_periods)
                                      : kNaN);
        };
        j["tip_within_sd"] = sd_periods == 0 ? Json()
                                             : Json{{"periods", sd_periods},
                                                    {"within_1_sd_share", sd_share(sd_one)},
                                                    {"within_2_sd_share", sd_share(sd_two)}};
        Json level_periods = Json::object();
        for (const char* level : {"warning_10N", "critical_14N"}) {
            std::size_t over = 0, up_over = 0, below = 0, up_below = 0;
            for (const Json& c : cases) {
                if (!c.contains("estimators") || !c["estimators"].contains(e.name)) continue;
                const Json& l =
                    member(member(c["estimators"][e.name], "contact_level_periods"), level);
                if (!l.is_object()) continue;
                over += l.value("periods_over", std::size_t{0});
                up_over += l.value("up_over", std::size_t{0});
                below += l.value("periods_below", std::size_t{0});
                up_below += l.value("up_below", std::size_t{0});
            }
            const auto share = [](std::size_t n, std::size_t of) {
                return num(of > 0 ? static_cast<double>(n) / static_cast<double>(of) : kNaN);
            };
            if (over + below > 0)
                level_periods[level] = {{"periods_over", over},
                                        {"up_over_share", share(up_over, over)},
                                        {"periods_below", below},
                                        {"up_below_share", share(up_below, below)}};
        }
        j["contact_level_periods"] = level_periods.empty() ? Json() : level_periods;
        j["tip_error_rms_mm"] = distribution_json(tip_rms);
        j["tip_error_max_mm"] = distribution_json(tip_max);
        j["force_error_rms_N"] = distribution_json(force_rms);
        for (const AlarmKind& kind : kAlarms) {
            std::size_t episodes = 0, detected = 0, late = 0, missed = 0, false_alarms = 0;
            double scored_s = 0;
            std::vector<double> latencies, lingers, false_rates, shares;
            for (const Json& c : cases) {
                if (!c.contains("estimators") || !c["estimators"].contains(e.name)) continue;
                const Json& a = c["estimators"][e.name][kind.key];
                episodes += a.value("episodes", std::size_t{0});
                detected += a.value("detected", std::size_t{0});
                late += a.value("late", std::size_t{0});
                missed += a.value("missed", std::size_t{0});
                false_alarms += a.value("false_alarms", std::size_t{0});
                scored_s += get(a, "scored_s");
                for (const Json& v : a["latency_s"])
                    if (v.is_number()) latencies.push_back(v.get<double>());
                for (const Json& v : a["linger_s"])
                    if (v.is_number()) lingers.push_back(v.get<double>());
                false_rates.push_back(get(a, "false_alarms_per_10min"));
                shares.push_back(get(a, "detected_share"));
            }
            std::vector<double> timely;
            for (double l : latencies)
                if (l <= AlarmRule{}.within_s) timely.push_back(l);
            j[kind.key] = {
                {"episodes", episodes},
                {"detected", detected},
                {"late", late},
                {"missed", missed},
                {"detected_share",
                 num(episodes > 0 ? static_cast<double>(detected) / static_cast<double>(episodes)
                                  : kNaN)},
                {"false_alarms", false_alarms},
                {"scored_s", scored_s},
                {"false_alarms_per_10min",
                 num(scored_s > 0 ? static_cast<double>(false_alarms) * 600.0 / scored_s : kNaN)},
                {"median_latency_s", num(quantile(latencies, 0.5))},
                {"median_latency_detected_s", num(quantile(timely, 0.5))},
                {"linger_s", distribution_json(lingers)},
                {"detected_share_by_case", distribution_json(shares)},
                {"false_alarms_per_10min_by_case", distribution_json(false_rates)}};
        }
        // Fault flags: the share of all scored periods, and its distribution over the cases.
        Json faults = Json::object();
        bool any = false;
        for (const std::string& flag : fault_flag_names()) {
            double set = 0, total = 0;
            std::vector<double> per_case;
            for (const Json& c : cases) {
                if (!c.contains("estimators") || !c["estimators"].contains(e.name)) continue;
                const Json& f = c["estimators"][e.name]["fault_share"];
                if (!f.is_object()) continue;
                any = true;
                const double share = get(f, flag.c_str());
                const double periods = get(c, "periods");
                per_case.push_back(share);
                if (std::isfinite(share) && std::isfinite(periods)) {
                    set += share * periods;
                    total += periods;
                }
            }
            Json d = distribution_json(per_case);
            d["pooled"] = num(total > 0 ? set / total : kNaN);
            faults[flag] = d;
        }
        j["fault_share"] = any ? faults : Json();
        estimators.push_back(j);
    }
    overall["estimators"] = estimators;

    // The procedures' outcome (physician runs report it in summary.json "procedure").
    Json procedure;
    std::map<std::string, std::pair<std::size_t, std::size_t>> by_style;  // reached, known
    std::vector<double> insertions;
    std::size_t known = 0;
    for (const Json& c : cases) {
        if (!c.contains("procedure") || !c["procedure"].is_object()) continue;
        const Json& p = c["procedure"];
        if (p.value("kind", "") != "physician") continue;
        ++known;
        auto& [reached, total] = by_style[c.value("style", "")];
        ++total;
        if (p["cecum_reached"].is_boolean() && p["cecum_reached"].get<bool>()) {
            ++reached;
            if (p["insertion_at_cecum_mm"].is_number())
                insertions.push_back(p["insertion_at_cecum_mm"].get<double>());
        }
    }
    if (known == 0) {
        procedure = nullptr;
    } else {
        Json styles = Json::object();
        for (const auto& [style, counts] : by_style)
            styles[style] = {{"cases", counts.second},
                             {"cecum_reached", counts.first},
                             {"cecal_intubation_rate", static_cast<double>(counts.first) /
                                                           static_cast<double>(counts.second)}};
        procedure["physician_cases"] = known;
        procedure["by_style"] = styles;
        std::size_t under = 0;
        for (double v : insertions)
            if (v < 1330.0) ++under;
        Json histogram = Json::array();
        for (int from = 500; from < 1800; from += 100) {
            std::size_t n = 0;
            for (double v : insertions)
                if (v >= from && v < from + 100) ++n;
            histogram.push_back({{"from_mm", from}, {"to_mm", from + 100}, {"cases", n}});
        }
        std::sort(insertions.begin(), insertions.end());
        procedure["insertion_at_cecum_mm"] = insertions;
        procedure["insertion_histogram"] = histogram;
        procedure["under_1330_mm"] = {
            {"cases", under},
            {"of", insertions.size()},
            {"share", num(insertions.empty() ? kNaN
                                             : static_cast<double>(under) /
                                                   static_cast<double>(insertions.size()))}};
    }
    overall["procedure"] = procedure;

    // The worst cases: by the box's tip error (the first estimator with a tip), then
    // by missed loop episodes.
    std::vector<std::pair<double, std::string>> ranked;
    for (const Json& c : cases) {
        if (c.value("status", "") != "complete") continue;
        double key = -1;
        for (const Estimator& e : estimator_registry()) {
            const Json& s = c["estimators"][e.name];
            if (s["tip_error_mm"].is_object()) {
                key = get(s["tip_error_mm"], "rms");
                break;
            }
        }
        ranked.emplace_back(key, c.value("case", ""));
    }
    std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
        return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    Json worst = Json::array();
    for (std::size_t i = 0; i < ranked.size() && i < 3; ++i)
        worst.push_back(ranked[i].second);
    overall["worst_cases"] = worst;
    return overall;
}

std::string scorecard_csv_header() {
    std::string h =
        "case,style,status,estimator,duration_s,tip_error_rms_mm,tip_error_max_mm,"
        "force_error_rms_N";
    for (const AlarmKind& kind : kAlarms) {
        const std::string p = std::string(kind.key).substr(0, std::string(kind.key).find('_'));
        for (const char* m : {"episodes", "detected", "late", "missed", "false_alarms",
                              "false_alarms_per_10min", "median_latency_s", "median_linger_s"})
            h += "," + p + "_" + m;
    }
    for (const std::string& flag : fault_flag_names())
        h += ",fault_" + flag + "_share";
    h += ",cecum_reached,insertion_at_cecum_mm";
    return h;
}

std::vector<std::string> scorecard_csv_rows(const Json& c) {
    std::vector<std::string> rows;
    const std::string head = csv_cell(c.value("case", "")) + "," + csv_cell(c.value("style", "")) +
                             "," + csv_cell(c.value("status", ""));
    std::string procedure = ",";
    if (c.contains("procedure") && c["procedure"].is_object()) {
        const Json& p = c["procedure"];
        procedure = std::string(p["cecum_reached"].is_boolean()
                                    ? (p["cecum_reached"].get<bool>() ? "1" : "0")
                                    : "") +
                    "," + csv_number(get(p, "insertion_at_cecum_mm"));
    }
    for (const Estimator& e : estimator_registry()) {
        std::string row = head + "," + e.name + "," + csv_number(get(c, "duration_s"));
        if (!c.contains("estimators") || !c["estimators"].contains(e.name)) {
            const std::size_t columns =
                3 + 8 * std::size(kAlarms) + fault_flag_names().size();  // left empty
            row += std::string(columns, ',');
            rows.push_back(row + "," + procedure);
            continue;
        }
        const Json& s = c["estimators"][e.name];
        auto add = [&row](double v) {
            row += ',';
            row += csv_number(v);
        };
        add(get(s["tip_error_mm"], "rms"));
        add(get(s["tip_error_mm"], "max"));
        add(get(s["force_error_N"], "rms"));
        for (const AlarmKind& kind : kAlarms) {
            const Json& a = s[kind.key];
            for (const char* m : {"episodes", "detected", "late", "missed", "false_alarms",
                                  "false_alarms_per_10min", "median_latency_s", "median_linger_s"})
                add(get(a, m));
        }
        for (const std::string& flag : fault_flag_names())
            add(s["fault_share"].is_object() ? get(s["fault_share"], flag.c_str()) : kNaN);
        rows.push_back(row + "," + procedure);
    }
    return rows;
}

std::string scorecard_markdown(const Json& overall, const std::string& manifest_name,
                               const std::string& description) {
    std::ostringstream md;
    md << "# Scorecard: `" << manifest_name << "`\n\n";
    if (!description.empty()) md << description << "\n\n";
    const std::size_t cases = overall.value("cases", std::size_t{0});
    const std::size_t scored = overall.value("scored", std::size_t{0});
    md << scored << " of " << cases << " cases scored";
    if (scored != cases) {
        md << " (not scored:";
        for (const Json& n : overall["not_scored"])
            md << " " << n.value("case", "") << " (" << n.value("status", "") << ")";
        md << ")";
    }
    md << "; " << fmt(get(overall, "simulated_s"), "%.1f") << " s simulated in "
       << fmt(get(overall, "simulation_wall_s"), "%.1f")
       << " s of the cases' own wall times (summed).";
    if (overall.contains("cut_short") && !overall["cut_short"].empty()) {
        md << " " << overall["cut_short"].size()
           << (overall["cut_short"].size() == 1 ? " of them was" : " of them were")
           << " scored only up to where the scope went through the colon wall (its "
              "axis more than 40 mm beyond it: the run is not physical after it):";
        for (const Json& c : overall["cut_short"])
            md << " " << c.value("case", "") << " ("
               << fmt(c.value("scope_through_wall_s", 0.0), "%.1f") << " of "
               << fmt(c.value("duration_s", 0.0), "%.1f") << " s)";
        md << ".";
    }
    md << " Distributions over the cases are given as "
          "median / 90th "
          "percentile / worst; detections, misses and false alarms are pooled over the cases. "
          "Rules: host_sim/evaluate/README.md.\n\n";
    const Json& estimators = overall["estimators"];
    md << "| measure |";
    for (const Json& e : estimators)
        md << " " << e.value("label", "") << " |";
    md << "\n|---|";
    for (std::size_t i = 0; i < estimators.size(); ++i)
        md << "---|";
    md << "\n";
    auto dist_row = [&](const std::string& title, auto pick) {
        md << "| " << title << " |";
        for (const Json& e : estimators) {
            const Json& d = pick(e);
            if (!d.is_object() || d.value("cases", std::size_t{0}) == 0)
                md << " n/a |";
            else
                md << " " << fmt_json(d, "median") << " / " << fmt_json(d, "p90") << " / "
                   << fmt_json(d, "worst") << " |";
        }
        md << "\n";
    };
    dist_row("tip position error, RMS [mm]",
             [](const Json& e) -> const Json& { return e["tip_error_rms_mm"]; });
    dist_row("tip position error, max [mm]",
             [](const Json& e) -> const Json& { return e["tip_error_max_mm"]; });
    md << "| tip within its stated uncertainty, 1 SD / 2 SD (pooled periods; Gaussian: 68 / 95 %) "
          "|";
    for (const Json& e : estimators) {
        const Json& w = member(e, "tip_within_sd");
        if (!w.is_object())
            md << " n/a |";
        else
            md << " " << fmt(100.0 * get(w, "within_1_sd_share"), "%.0f") << " / "
               << fmt(100.0 * get(w, "within_2_sd_share"), "%.0f") << " % |";
    }
    md << "\n";
    dist_row("largest contact force error, RMS [N]",
             [](const Json& e) -> const Json& { return e["force_error_rms_N"]; });
    for (const AlarmKind& kind : kAlarms) {
        const std::string key = kind.key;
        md << "| " << kind.title << ": episodes detected within 0.5 s (late, missed) |";
        for (const Json& e : estimators) {
            const Json& a = e[key];
            const std::size_t n = a.value("episodes", std::size_t{0});
            if (n == 0) {
                md << " no episode |";
                continue;
            }
            md << " " << a.value("detected", std::size_t{0}) << " of " << n << " ("
               << fmt(100.0 * get(a, "detected_share"), "%.0f") << " %; "
               << a.value("late", std::size_t{0}) << " late, " << a.value("missed", std::size_t{0})
               << " missed) |";
        }
        md << "\n| " << kind.title << ": median latency, detected and late [s] |";
        for (const Json& e : estimators)
            md << " " << fmt_json(e[key], "median_latency_s") << " |";
        md << "\n| " << kind.title << ": false alarms per 10 min (count) |";
        for (const Json& e : estimators)
            md << " " << fmt_json(e[key], "false_alarms_per_10min") << " ("
               << e[key].value("false_alarms", std::size_t{0}) << ") |";
        md << "\n";
        dist_row(kind.title + std::string(": up after the episode ends [s]"),
                 [&](const Json& e) -> const Json& { return e[key]["linger_s"]; });
        const char* level = key == "warning_alarm"    ? "warning_10N"
                            : key == "critical_alarm" ? "critical_14N"
                                                      : nullptr;
        if (level == nullptr) continue;
        md << "| " << kind.title
           << ": up in the periods the truth is over it / under 90 % of it (pooled) |";
        for (const Json& e : estimators) {
            const Json& l = member(member(e, "contact_level_periods"), level);
            if (!l.is_object())
                md << " n/a |";
            else
                md << " " << fmt(100.0 * get(l, "up_over_share"), "%.0f") << " / "
                   << fmt(100.0 * get(l, "up_below_share"), "%.0f") << " % |";
        }
        md << "\n";
    }
    // Fault flags set in any period.
    for (const std::string& flag : fault_flag_names()) {
        bool any = false;
        for (const Json& e : estimators)
            any =
                any || (e["fault_share"].is_object() && get(e["fault_share"][flag], "pooled") > 0);
        if (!any) continue;
        md << "| periods with the fault flag `" << flag << "` (pooled) |";
        for (const Json& e : estimators)
            md << " "
               << (e["fault_share"].is_object() ? percent(get(e["fault_share"][flag], "pooled"))
                                                : std::string("n/a"))
               << " |";
        md << "\n";
    }
    md << "\n**Procedures** (physician runs: summary.json \"procedure\"): ";
    const Json& p = overall["procedure"];
    if (!p.is_object()) {
        md << "n/a (no case of this set reports its procedure's outcome).\n";
    } else {
        md << "\n\n| style | cases | cecum reached | cecal intubation rate |\n|---|---|---|---|\n";
        for (const auto& [style, s] : p["by_style"].items())
            md << "| " << style << " | " << s.value("cases", std::size_t{0}) << " | "
               << s.value("cecum_reached", std::size_t{0}) << " | "
               << fmt(100.0 * get(s, "cecal_intubation_rate"), "%.0f") << " % |\n";
        const Json& u = p["under_1330_mm"];
        md << "\nInsertion at cecal intubation: " << u.value("cases", std::size_t{0}) << " of "
           << u.value("of", std::size_t{0}) << " under 1,330 mm ("
           << fmt(100.0 * get(u, "share"), "%.0f") << " %). Histogram (100 mm bins):";
        for (const Json& b : p["insertion_histogram"])
            if (b.value("cases", std::size_t{0}) > 0)
                md << " " << b.value("from_mm", 0) << "-" << b.value("to_mm", 0)
                   << " mm: " << b.value("cases", std::size_t{0}) << ";";
        md << "\n";
    }
    md << "\nWorst cases (by the box's tip error):";
    for (const Json& w : overall["worst_cases"])
        md << " " << w.get<std::string>();
    md << "\n";
    return md.str();
}

}  // namespace scopekin::evaluate
