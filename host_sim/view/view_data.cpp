#include "host_sim/view/view_data.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "host_sim/evaluate/case_run.hpp"
#include "host_sim/evaluate/estimators.hpp"
#include "model/io/strict_json.hpp"

namespace scopekin::view {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

/// [start_s, end_s) intervals where `up(k)` holds over the periods; end_s null: up at the end.
Json intervals(const std::vector<double>& time_s, const std::function<bool(std::size_t)>& up,
               const Json& extra) {
    Json out = Json::array();
    std::size_t k = 0;
    while (k < time_s.size()) {
        if (!up(k)) {
            ++k;
            continue;
        }
        Json item = extra;
        item["start_s"] = time_s[k];
        while (k < time_s.size() && up(k))
            ++k;
        item["end_s"] = k < time_s.size() ? Json(time_s[k]) : Json(nullptr);
        out.push_back(item);
    }
    return out;
}

Json episodes_json(const std::vector<evaluate::Episode>& list) {
    Json out = Json::array();
    for (const evaluate::Episode& e : list)
        out.push_back({{"onset_s", e.onset_s},
                       {"end_s", e.end_s ? Json(*e.end_s) : Json(nullptr)},
                       {"label", e.label}});
    return out;
}

/// The box's alarms (firmware.csv self_lock_alarm, contact_force_level 1 and 2) in time order.
Json alarms_json(const evaluate::CaseRun& run) {
    Json all = Json::array();
    const auto add = [&](const Json& list) {
        for (const Json& a : list)
            all.push_back(a);
    };
    add(intervals(run.time_s, [&](std::size_t k) { return run.box_self_lock[k] != 0; },
                  {{"kind", "self_lock"}}));
    add(intervals(run.time_s, [&](std::size_t k) { return run.box_contact_level[k] == 1; },
                  {{"kind", "contact_force_warning"}}));
    add(intervals(run.time_s, [&](std::size_t k) { return run.box_contact_level[k] >= 2; },
                  {{"kind", "contact_force_critical"}}));
    std::stable_sort(all.begin(), all.end(), [](const Json& a, const Json& b) {
        return a["start_s"].get<double>() < b["start_s"].get<double>();
    });
    return all;
}

Json faults_json(const evaluate::CaseRun& run) {
    Json all = Json::array();
    const std::vector<std::string>& names = evaluate::fault_flag_names();
    for (std::size_t bit = 0; bit < names.size(); ++bit)
        for (const Json& f :
             intervals(run.time_s,
                       [&](std::size_t k) { return ((run.box_fault_flags[k] >> bit) & 1U) != 0; },
                       {{"flag", names[bit]}}))
            all.push_back(f);
    return all;
}

/// The station columns of firmware.csv (station_K_path_mm, station_K_normal_N), K from 0 up.
std::size_t station_count(const fs::path& firmware_csv) {
    std::ifstream in(firmware_csv);
    std::string header;
    std::getline(in, header);
    std::size_t k = 0;
    while (header.find(",station_" + std::to_string(k) + "_path_mm,") != std::string::npos)
        ++k;
    return k;
}

/// One row of every k-th period (at most max_points rows), the series the timeline draws.
Json series_json(const evaluate::CaseRun& run, const fs::path& folder, std::size_t max_points) {
    const std::size_t n = run.time_s.size();
    const std::size_t stride = std::max<std::size_t>(1, (n + max_points - 1) / max_points);
    const fs::path fw = folder / "firmware.csv";
    const std::size_t stations = station_count(fw);
    std::vector<std::string> names;
    for (std::size_t k = 0; k < stations; ++k) {
        names.push_back("station_" + std::to_string(k) + "_path_mm");
        names.push_back("station_" + std::to_string(k) + "_normal_N");
    }
    std::vector<std::vector<double>> station_columns;
    try {
        if (stations > 0) station_columns = evaluate::read_number_columns(fw, names);
    } catch (const evaluate::CaseDataError& e) {
        throw ViewDataError(e.what());
    }
    Json s;
    const auto pick = [&](const std::vector<double>& v) {
        Json out = Json::array();
        for (std::size_t k = 0; k < n; k += stride)
            out.push_back(k < v.size() && std::isfinite(v[k]) ? Json(v[k]) : Json(nullptr));
        return out;
    };
    s["stride_periods"] = stride;
    s["time_s"] = pick(run.time_s);
    s["handle_force_N"] = pick(run.handle_force_N);
    s["handle_torque_Nmm"] = pick(run.handle_torque_Nmm);
    s["insertion_mm"] = pick(run.insertion_mm);
    s["true_tip_path_mm"] = pick(run.true_tip_path_mm);
    s["box_tip_path_mm"] = pick(run.box_tip_path_mm);
    s["box_tip_sd_mm"] = pick(run.box_tip_uncertainty_mm);
    s["true_max_force_N"] = pick(run.true_max_station_force_N);
    s["box_max_force_N"] = pick(run.box_max_contact_force_N);
    Json paths = Json::array(), normals = Json::array();
    for (std::size_t k = 0; k < n; k += stride) {
        Json p = Json::array(), f = Json::array();
        for (std::size_t st = 0; st < stations; ++st) {
            p.push_back(station_columns[2 * st][k]);
            f.push_back(station_columns[2 * st + 1][k]);
        }
        paths.push_back(p);
        normals.push_back(f);
    }
    s["station_path_mm"] = paths;
    s["station_normal_N"] = normals;
    return s;
}

void require_array(const Json& j, const char* key, const std::string& where) {
    if (!j.contains(key) || !j[key].is_array())
        throw ViewDataError(where + ": no \"" + key + "\" list");
}

/// A frame from a snapshot or a frames.jsonl line: time_s, scope_mm, colon_mm, contacts.
Json frame_json(const Json& j, const std::string& where) {
    if (!j.is_object() || !j.contains("time_s") || !j["time_s"].is_number())
        throw ViewDataError(where + ": not a frame (no \"time_s\")");
    require_array(j, "scope_mm", where);
    require_array(j, "colon_mm", where);
    Json f = {{"time_s", j["time_s"]}, {"scope_mm", j["scope_mm"]}, {"colon_mm", j["colon_mm"]}};
    f["label"] = j.contains("label") && j["label"].is_string() ? j["label"] : Json("");
    Json contacts = Json::array();
    for (const Json& c : j.value("contacts", Json::array()))
        contacts.push_back({{"position_mm", c.at("position_mm")},
                            {"force_N", c.at("force_N")},
                            {"normal_force_N", c.at("normal_force_N")}});
    f["contacts"] = contacts;
    return f;
}

Json frames_from_jsonl(const fs::path& file) {
    std::ifstream in(file);
    if (!in) throw ViewDataError(file.string() + ": cannot be read");
    Json frames = Json::array();
    std::string line;
    std::size_t number = 0;
    while (std::getline(in, line)) {
        ++number;
        if (line.empty()) continue;
        const std::string where = file.string() + ": line " + std::to_string(number);
        Json j;
        try {
            j = Json::parse(line);
            frames.push_back(frame_json(j, where));
        } catch (const Json::exception& e) {
            throw ViewDataError(where + ": not a frame (" + e.what() + "; a truncated file?)");
        }
    }
    return frames;
}

}  // namespace

Json read_run_view(const fs::path& folder, std::size_t max_series_points) {
    if (!fs::is_directory(folder)) throw ViewDataError(folder.string() + ": not a folder");
    if (!fs::is_regular_file(folder / "summary.json"))
        throw ViewDataError(folder.string() +
                            ": no run here (no summary.json; `scopekin simulate`, `scopekin demo` "
                            "and each case of `scopekin evaluate` write one when a run ends)");
    evaluate::CaseRun run;
    try {
        run = evaluate::read_case_run(folder);
    } catch (const evaluate::CaseDataError& e) {
        throw ViewDataError(e.what());
    }
    if (run.status != "complete")
        throw ViewDataError((folder / "summary.json").string() + ": the run did not complete (" +
                            run.message +
                            "); its files end at the failure, as NAME.incomplete.csv");
    if (run.time_s.empty()) throw ViewDataError((folder / "truth.csv").string() + ": no rows");

    const fs::path snapshots_file = folder / "snapshots.json";
    Json snapshots;
    try {
        snapshots = model::io::parse_json_file(snapshots_file.string());
    } catch (const std::exception& e) {
        throw ViewDataError(std::string(e.what()) + " (the colon's shape is read from it)");
    }
    if (!snapshots.is_object() || !snapshots.contains("colon"))
        throw ViewDataError(snapshots_file.string() + ": no \"colon\"");
    const Json& colon = snapshots["colon"];
    for (const char* key : {"centerline_mm", "inner_radius_mm", "region"})
        require_array(colon, key, snapshots_file.string() + ": colon");

    Json data;
    data["schema"] = "scopekin-view/1";
    data["kind"] = "run";
    data["title"] = fs::absolute(folder).lexically_normal().filename().string();
    const Json summary = model::io::parse_json_file((folder / "summary.json").string());
    data["subtitle"] = summary.value("description", std::string()) + " · " +
                       std::to_string(static_cast<int>(std::round(run.duration_s))) +
                       " s simulated";
    data["colon"] = {{"centerline_mm", colon["centerline_mm"]},
                     {"inner_radius_mm", colon["inner_radius_mm"]},
                     {"region", colon["region"]}};
    const fs::path frames_file = folder / "frames.jsonl";
    if (fs::is_regular_file(frames_file)) {
        data["frames"] = frames_from_jsonl(frames_file);
        data["frames_source"] = "frames.jsonl";
    } else {
        Json frames = Json::array();
        require_array(snapshots, "snapshots", snapshots_file.string());
        for (std::size_t k = 0; k < snapshots["snapshots"].size(); ++k) {
            const std::string where =
                snapshots_file.string() + ": snapshots[" + std::to_string(k) + "]";
            try {
                frames.push_back(frame_json(snapshots["snapshots"][k], where));
            } catch (const Json::exception& e) {
                throw ViewDataError(where + ": " + e.what());
            }
        }
        std::stable_sort(frames.begin(), frames.end(), [](const Json& a, const Json& b) {
            return a["time_s"].get<double>() < b["time_s"].get<double>();
        });
        data["frames"] = frames;
        data["frames_source"] = "snapshots.json";
    }
    data["series"] = series_json(run, folder, std::max<std::size_t>(max_series_points, 2));
    data["alarms"] = alarms_json(run);
    data["faults"] = faults_json(run);
    data["truth_episodes"] = {{"loop", episodes_json(run.loop_episodes)},
                              {"warning_10N", episodes_json(run.warning_episodes)},
                              {"critical_14N", episodes_json(run.critical_episodes)}};
    return data;
}

bool is_evaluation_folder(const fs::path& folder) {
    return fs::is_regular_file(folder / "scorecard.json") && fs::is_directory(folder / "cases");
}

Json read_evaluation_view(
    const fs::path& folder,
    const std::function<void(std::size_t, std::size_t, const std::string&)>& progress) {
    const fs::path file = folder / "scorecard.json";
    Json scorecard;
    try {
        scorecard = model::io::parse_json_file(file.string());
    } catch (const std::exception& e) {
        throw ViewDataError(e.what());
    }
    if (!scorecard.is_object() || !scorecard.contains("cases") || !scorecard["cases"].is_array() ||
        !scorecard.contains("overall"))
        throw ViewDataError(file.string() +
                            ": not a scorecard (no \"cases\" list or no \"overall\")");
    Json data;
    data["schema"] = "scopekin-view/1";
    data["kind"] = "evaluation";
    data["title"] = "evaluation " + scorecard.value("manifest", std::string("?"));
    data["subtitle"] = scorecard.value("description", std::string());
    data["scorecard"] = scorecard;
    Json views = Json::object(), errors = Json::object();
    const Json& cases = scorecard["cases"];
    for (std::size_t k = 0; k < cases.size(); ++k) {
        const std::string name = cases[k].value("case", std::string());
        const std::string sub = cases[k].value("folder", "cases/" + name);
        if (progress) progress(k, cases.size(), name);
        if (cases[k].value("status", std::string()) != "complete") {
            errors[name] = "the run did not complete: " + cases[k].value("message", std::string());
            continue;
        }
        try {
            Json view = read_run_view(folder / sub, kEvaluationCaseSeriesPoints);
            view["title"] = name;
            views[name] = view;
        } catch (const ViewDataError& e) {
            errors[name] = e.what();
        }
    }
    data["case_views"] = views;
    data["case_errors"] = errors;
    return data;
}

bool is_discrepancy_folder(const fs::path& folder) {
    return fs::is_regular_file(folder / "report.json") &&
           fs::is_regular_file(folder / "series.csv");
}

Json read_discrepancy_view(const fs::path& folder) {
    Json report;
    try {
        report = model::io::parse_json_file((folder / "report.json").string());
    } catch (const std::exception& e) {
        throw ViewDataError(e.what());
    }
    if (!report.is_object() || !report.contains("verdict"))
        throw ViewDataError((folder / "report.json").string() + ": not a discrepancy report");
    const fs::path file = folder / "series.csv";
    std::ifstream in(file);
    std::string line;
    if (!in || !std::getline(in, line))
        throw ViewDataError(file.string() + ": cannot be read, or empty");
    if (line != "output,component,time_s,held_out,measured,before,after")
        throw ViewDataError(file.string() + ": line 1: not series.csv's header");
    // Each output's rows in order, kept whole; thinned to kMaxSeriesPoints below.
    std::map<std::string, std::vector<std::array<double, 5>>> rows;
    std::size_t number = 1;
    while (std::getline(in, line)) {
        ++number;
        if (line.empty()) continue;
        std::vector<std::string> cells;
        std::size_t from = 0;
        for (std::size_t at = line.find(',');; at = line.find(',', from)) {
            cells.push_back(
                line.substr(from, at == std::string::npos ? std::string::npos : at - from));
            if (at == std::string::npos) break;
            from = at + 1;
        }
        const std::string where = file.string() + ": line " + std::to_string(number);
        if (cells.size() != 7)
            throw ViewDataError(where + ": " + std::to_string(cells.size()) +
                                " cells, not 7 (a truncated file?)");
        std::array<double, 5> values{};
        for (std::size_t k = 0; k < 5; ++k) {
            const std::string& text = cells[2 + k];
            const auto r = std::from_chars(text.data(), text.data() + text.size(), values[k]);
            if (text.empty() || r.ec != std::errc() || r.ptr != text.data() + text.size() ||
                !std::isfinite(values[k]))
                throw ViewDataError(where + ": '" + text + "' is not a number");
        }
        rows[cells[0] + "/" + cells[1]].push_back(values);
    }
    Json series = Json::object();
    for (const auto& [key, list] : rows) {
        const std::size_t stride =
            std::max<std::size_t>(1, (list.size() + kMaxSeriesPoints - 1) / kMaxSeriesPoints);
        Json t = Json::array(), held = Json::array(), measured = Json::array(),
             before = Json::array(), after = Json::array();
        for (std::size_t k = 0; k < list.size(); k += stride) {
            t.push_back(list[k][0]);
            held.push_back(list[k][1] != 0.0 ? 1 : 0);
            measured.push_back(list[k][2]);
            before.push_back(list[k][3]);
            after.push_back(list[k][4]);
        }
        series[key] = {{"time_s", t},
                       {"held_out", held},
                       {"measured", measured},
                       {"before", before},
                       {"after", after}};
    }
    Json data;
    data["schema"] = "scopekin-view/1";
    data["kind"] = "discrepancy";
    data["title"] = "discrepancy " + fs::absolute(folder).lexically_normal().filename().string();
    data["subtitle"] = "recording " + report.value("recording", std::string("?")) + " · model " +
                       report.value("model", std::string("?"));
    data["report"] = report;
    data["series"] = series;
    return data;
}

}  // namespace scopekin::view
