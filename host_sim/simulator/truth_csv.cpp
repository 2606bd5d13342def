#include "host_sim/simulator/truth_csv.hpp"

#include <cinttypes>
#include <cmath>
#include <cstdio>

#include "model/truth/truth_definitions.hpp"

namespace scopekin::host_sim {
namespace {

using Json = nlohmann::ordered_json;
namespace truth = model::truth;

std::string num(double v) {
    if (!std::isfinite(v)) return {};
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.7g", v);
    return buffer;
}

std::string period_time(std::uint64_t time_us) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%" PRIu64 ".%06" PRIu64, time_us / 1000000U,
                  time_us % 1000000U);
    return buffer;
}

Json optional_time(const std::optional<double>& t) {
    return t ? Json(*t) : Json(nullptr);
}

}  // namespace

TruthSample truth_sample(const model::truth::TruthReadout& r) {
    TruthSample s;
    s.time_s = r.time_s;
    s.insertion_mm = r.insertion_mm;
    s.tip_path_mm = r.tip_path_mm;
    s.tip_displaced_path_mm = r.tip_displaced_path_mm;
    s.tip_region = r.tip_region;
    for (const model::truth::StationTruth& st : r.stations) {
        s.station_force_N.push_back(st.force_N);
        s.station_inside.push_back(st.inside);
    }
    s.max_station_force_N = r.max_station_force_N;
    s.max_station = r.max_station;
    s.max_wall_force_N = r.max_wall_force_N;
    s.max_wall_path_mm = r.max_wall_path_mm;
    s.max_wall_region = r.max_wall_region;
    s.has_wall_force = r.has_wall_force;
    s.bow_region = r.bow_region;
    s.bow_mm = r.bow_mm;
    s.region_bow_mm = r.region_bow_mm;
    s.scope_crosses = r.scope_crosses;
    s.scope_beyond_wall_mm = r.scope_beyond_wall_mm;
    return s;
}

TruthSample blend(const TruthSample& a, const TruthSample& b, double w) {
    const auto mix = [w](double x, double y) { return x + w * (y - x); };
    TruthSample r = w < 0.5 ? a : b;  // labels, flags and indices from the nearer one
    r.scope_beyond_wall_mm = std::max(a.scope_beyond_wall_mm, b.scope_beyond_wall_mm);
    r.time_s = mix(a.time_s, b.time_s);
    r.insertion_mm = mix(a.insertion_mm, b.insertion_mm);
    r.tip_path_mm = mix(a.tip_path_mm, b.tip_path_mm);
    r.tip_displaced_path_mm = mix(a.tip_displaced_path_mm, b.tip_displaced_path_mm);
    for (std::size_t k = 0; k < r.station_force_N.size() && k < a.station_force_N.size() &&
                            k < b.station_force_N.size();
         ++k)
        r.station_force_N[k] =
            a.station_force_N[k] + w * (b.station_force_N[k] - a.station_force_N[k]);
    r.max_station_force_N = 0;
    for (std::size_t k = 0; k < r.station_force_N.size(); ++k)
        if (r.station_force_N[k].norm() > r.max_station_force_N) {
            r.max_station_force_N = r.station_force_N[k].norm();
            r.max_station = k;
        }
    r.max_wall_force_N = mix(a.max_wall_force_N, b.max_wall_force_N);
    r.bow_mm = mix(a.bow_mm, b.bow_mm);
    for (std::size_t k = 0; k < r.region_bow_mm.size(); ++k)
        r.region_bow_mm[k] = mix(a.region_bow_mm[k], b.region_bow_mm[k]);
    return r;
}

void TruthRecorder::add(const TruthSample& sample) {
    samples_.push_back(sample);
}

std::vector<TruthSample> TruthRecorder::at_periods(
    const std::vector<std::uint64_t>& period_us) const {
    std::vector<TruthSample> out;
    if (samples_.empty()) return out;
    out.reserve(period_us.size());
    std::size_t j = 0;  // samples_[j] is the last readout at or before the period
    for (std::uint64_t us : period_us) {
        const double t = static_cast<double>(us) * 1e-6;
        while (j + 1 < samples_.size() && samples_[j + 1].time_s <= t + 1e-9)
            ++j;
        TruthSample s;
        if (j + 1 >= samples_.size() || samples_[j].time_s >= t - 1e-9) {
            s = samples_[j];
        } else {
            const TruthSample& a = samples_[j];
            const TruthSample& b = samples_[j + 1];
            s = blend(a, b, (t - a.time_s) / (b.time_s - a.time_s));
        }
        s.time_s = t;
        out.push_back(std::move(s));
    }
    return out;
}

std::string truth_csv_header(std::size_t stations) {
    std::string h = "time_s,period,insertion_mm,tip_path_mm,tip_displaced_path_mm,tip_region";
    for (std::size_t k = 0; k < stations; ++k) {
        const std::string s = "station_" + std::to_string(k) + "_";
        h += "," + s + "inside," + s + "normal_N," + s + "tangential_N," + s + "side_N";
    }
    h += ",max_station_force_N,max_station,max_wall_force_N,max_wall_path_mm,max_wall_region,"
         "advance_efficiency,loop_excess_mm,loop_episode,loop_type,loop_region,force_level,"
         "force_warning_episode,force_critical_episode,scope_beyond_wall_mm";
    return h;
}

nlohmann::ordered_json TruthRecorder::write(std::ostream* out,
                                            const std::vector<std::uint64_t>& period_us,
                                            std::size_t stations) const {
    const std::vector<TruthSample> rows = at_periods(period_us);
    truth::RunSeries run;
    std::vector<double> force;
    for (const TruthSample& s : rows) {
        run.time_s.push_back(s.time_s);
        run.insertion_mm.push_back(s.insertion_mm);
        run.tip_path_mm.push_back(s.tip_path_mm);
        force.push_back(s.max_station_force_N);
    }
    const truth::LoopAnalysis loops = truth::loop_episodes(run);
    const std::vector<double> efficiency = truth::advance_efficiency(run);
    const std::vector<truth::ForceEpisode> warnings =
        truth::force_episodes(run.time_s, force, truth::kForceWarning_N);
    const std::vector<truth::ForceEpisode> criticals =
        truth::force_episodes(run.time_s, force, truth::kForceCritical_N);
    const auto label = [&](const std::vector<truth::ForceEpisode>& episodes) {
        std::vector<int> number(rows.size(), 0);
        for (std::size_t e = 0; e < episodes.size(); ++e)
            for (std::size_t i = episodes[e].onset; i < episodes[e].end.value_or(rows.size()); ++i)
                number[i] = static_cast<int>(e + 1);
        return number;
    };
    const std::vector<int> warning_number = label(warnings);
    const std::vector<int> critical_number = label(criticals);

    std::vector<std::string> types, regions;
    for (const truth::LoopEpisode& e : loops.episodes) {
        const truth::LoopShape shape = truth::classify_loop(
            rows[e.onset].region_bow_mm, rows[e.peak].region_bow_mm, rows[e.peak].scope_crosses);
        types.push_back(shape.type);
        regions.push_back(std::string(model::region_name(shape.region)));
    }

    if (out != nullptr) {
        *out << truth_csv_header(stations) << '\n';
        std::string line;
        for (std::size_t i = 0; i < rows.size(); ++i) {
            const TruthSample& s = rows[i];
            line = period_time(period_us[i]);
            line += ',' + std::to_string(i) + ',' + num(s.insertion_mm) + ',' + num(s.tip_path_mm) +
                    ',' + num(s.tip_displaced_path_mm) + ',' +
                    std::string(model::region_name(s.tip_region));
            for (std::size_t k = 0; k < stations; ++k) {
                const bool have = k < s.station_force_N.size();
                const Eigen::Vector3d f = have ? s.station_force_N[k] : Eigen::Vector3d::Zero();
                line += ',' + std::string(have && s.station_inside[k] ? "1" : "0") + ',' +
                        num(f.x()) + ',' + num(f.y()) + ',' + num(f.z());
            }
            const int episode = loops.episode[i];
            line += ',' + num(s.max_station_force_N) + ',' + std::to_string(s.max_station) + ',' +
                    num(s.max_wall_force_N) + ',' +
                    (s.has_wall_force ? num(s.max_wall_path_mm) : std::string()) + ',' +
                    (s.has_wall_force ? std::string(model::region_name(s.max_wall_region))
                                      : std::string()) +
                    ',' + num(efficiency[i]) + ',' + num(loops.excess_mm[i]) + ',' +
                    std::to_string(episode) + ',' +
                    (episode > 0 ? types[static_cast<std::size_t>(episode - 1)] : std::string()) +
                    ',' +
                    (episode > 0 ? regions[static_cast<std::size_t>(episode - 1)] : std::string()) +
                    ',' +
                    std::to_string(critical_number[i] > 0  ? 2
                                   : warning_number[i] > 0 ? 1
                                                           : 0) +
                    ',' + std::to_string(warning_number[i]) + ',' +
                    std::to_string(critical_number[i]) + ',' + num(s.scope_beyond_wall_mm) + '\n';
            *out << line;
        }
    }

    Json section;
    section["file"] = "truth.csv";
    section["periods"] = rows.size();
    section["definitions"] = {{"document", "model/truth/README.md"},
                              {"pace_window_s", truth::kPaceWindow_s},
                              {"pace_fraction", truth::kPaceFraction},
                              {"pace_min_handle_mm", truth::kPaceMinHandle_mm},
                              {"loop_onset_excess_mm", truth::kLoopOnsetExcess_mm},
                              {"loop_end_excess_mm", truth::kLoopEndExcess_mm},
                              {"loop_end_pace_s", truth::kLoopEndPace_s},
                              {"efficiency_window_s", truth::kEfficiencyWindow_s},
                              {"efficiency_min_handle_mm", truth::kEfficiencyMinHandle_mm},
                              {"force_warning_N", truth::kForceWarning_N},
                              {"force_critical_N", truth::kForceCritical_N},
                              {"force_clear_fraction", truth::kForceClearFraction},
                              {"force_merge_gap_s", truth::kForceMergeGap_s}};
    Json loop_list = Json::array();
    for (std::size_t e = 0; e < loops.episodes.size(); ++e) {
        const truth::LoopEpisode& ep = loops.episodes[e];
        loop_list.push_back(
            {{"episode", e + 1},
             {"type", types[e]},
             {"region", regions[e]},
             {"onset_s", ep.onset_s},
             {"detected_s", ep.detected_s},
             {"end_s", optional_time(ep.end_s)},
             {"end_reason", ep.end_reason.empty() ? Json(nullptr) : Json(ep.end_reason)},
             {"peak_s", rows[ep.peak].time_s},
             {"peak_excess_mm", ep.peak_excess_mm},
             {"onset_insertion_mm", rows[ep.onset].insertion_mm},
             {"onset_tip_path_mm", rows[ep.onset].tip_path_mm}});
    }
    section["loop_episodes"] = loop_list;
    // The first period at which the scope had gone through the colon wall: from there on the run
    // is not physical (TruthReader::kThroughWall_mm), and the scorecard scores the case only
    // before it.
    std::optional<double> through_s;
    for (const TruthSample& s : rows)
        if (s.scope_beyond_wall_mm > truth::TruthReader::kThroughWall_mm) {
            through_s = s.time_s;
            break;
        }
    section["scope_through_wall_s"] = optional_time(through_s);
    section["through_wall_mm"] = truth::TruthReader::kThroughWall_mm;
    const auto force_list = [&](const std::vector<truth::ForceEpisode>& episodes) {
        Json list = Json::array();
        for (std::size_t e = 0; e < episodes.size(); ++e) {
            const truth::ForceEpisode& ep = episodes[e];
            const TruthSample& peak = rows[ep.peak];
            list.push_back({{"episode", e + 1},
                            {"onset_s", ep.onset_s},
                            {"end_s", optional_time(ep.end_s)},
                            {"peak_s", peak.time_s},
                            {"peak_N", ep.peak_N},
                            {"peak_station", peak.max_station}});
        }
        return list;
    };
    section["force_episodes"] = {{"warning_10N", force_list(warnings)},
                                 {"critical_14N", force_list(criticals)}};
    return section;
}

}  // namespace scopekin::host_sim
