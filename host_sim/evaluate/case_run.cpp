#include "host_sim/evaluate/case_run.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "host_sim/recording/recording_reader.hpp"
#include "model/io/strict_json.hpp"
#include "model/truth/truth_readout.hpp"

namespace scopekin::evaluate {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The cells of the wanted columns of a CSV file without quoted cells (firmware.csv,
/// truth.csv): one vector of texts per wanted column, and each row's time_s text.
struct Columns {
    std::vector<std::vector<std::string>> cells;  ///< [wanted column][row]
    std::vector<std::size_t> lines;               ///< the 1-based line of each row
};

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> out;
    std::string cell;
    std::istringstream in(line);
    while (std::getline(in, cell, ','))
        out.push_back(cell);
    if (!line.empty() && line.back() == ',') out.emplace_back();
    return out;
}

bool has_column(const fs::path& file, const std::string& name) {
    std::ifstream in(file);
    std::string line;
    if (!in || !std::getline(in, line)) return false;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string> header = split(line);
    return std::find(header.begin(), header.end(), name) != header.end();
}

Columns read_columns(const fs::path& file, const std::vector<std::string>& wanted) {
    std::ifstream in(file);
    if (!in) throw CaseDataError(file.string() + ": cannot be read (the run did not write it)");
    std::string line;
    if (!std::getline(in, line)) throw CaseDataError(file.string() + ": empty");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string> header = split(line);
    std::vector<std::size_t> index;
    for (const std::string& w : wanted) {
        std::size_t k = 0;
        while (k < header.size() && header[k] != w)
            ++k;
        if (k == header.size())
            throw CaseDataError(file.string() + ": line 1: missing column '" + w + "'");
        index.push_back(k);
    }
    Columns c;
    c.cells.resize(wanted.size());
    std::size_t number = 1;
    while (std::getline(in, line)) {
        ++number;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) continue;
        const std::vector<std::string> cells = split(line);
        if (cells.size() != header.size())
            throw CaseDataError(file.string() + ": line " + std::to_string(number) + ": " +
                                std::to_string(cells.size()) + " cells, the header has " +
                                std::to_string(header.size()));
        for (std::size_t w = 0; w < wanted.size(); ++w)
            c.cells[w].push_back(cells[index[w]]);
        c.lines.push_back(number);
    }
    return c;
}

double number(const std::string& text, const fs::path& file, std::size_t line,
              const std::string& column) {
    if (text.empty()) return kNaN;
    double v = 0;
    const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
    if (r.ec != std::errc() || r.ptr != text.data() + text.size() || !std::isfinite(v))
        throw CaseDataError(file.string() + ": line " + std::to_string(line) + ", column " +
                            column + ": " + model::io::quote_text(text) + " is not a number");
    return v;
}

std::vector<double> numbers(const Columns& c, std::size_t w, const fs::path& file,
                            const std::string& column) {
    std::vector<double> out;
    out.reserve(c.cells[w].size());
    for (std::size_t r = 0; r < c.cells[w].size(); ++r)
        out.push_back(number(c.cells[w][r], file, c.lines[r], column));
    return out;
}

template <typename T>
std::vector<T> whole(const Columns& c, std::size_t w, const fs::path& file,
                     const std::string& column) {
    std::vector<T> out;
    out.reserve(c.cells[w].size());
    for (std::size_t r = 0; r < c.cells[w].size(); ++r) {
        const std::string& text = c.cells[w][r];
        std::uint64_t v = 0;
        const auto res = std::from_chars(text.data(), text.data() + text.size(), v);
        if (text.empty() || res.ec != std::errc() || res.ptr != text.data() + text.size() ||
            v > std::numeric_limits<T>::max())
            throw CaseDataError(file.string() + ": line " + std::to_string(c.lines[r]) +
                                ", column " + column + ": " + model::io::quote_text(text) +
                                " is not a whole number in range");
        out.push_back(static_cast<T>(v));
    }
    return out;
}

std::optional<double> optional_number(const Json& j, const char* key) {
    if (!j.contains(key) || !j[key].is_number()) return std::nullopt;
    return j[key].get<double>();
}

}  // namespace

std::vector<std::vector<double>> read_number_columns(const fs::path& file,
                                                     const std::vector<std::string>& names) {
    const Columns c = read_columns(file, names);
    std::vector<std::vector<double>> out;
    for (std::size_t w = 0; w < names.size(); ++w)
        out.push_back(numbers(c, w, file, names[w]));
    return out;
}

std::vector<Episode> read_episodes(const Json& list, const std::string& where) {
    std::vector<Episode> out;
    if (!list.is_array()) throw CaseDataError(where + ": expected a list of episodes");
    for (std::size_t i = 0; i < list.size(); ++i) {
        const Json& e = list[i];
        if (!e.is_object() || !e.contains("onset_s") || !e["onset_s"].is_number())
            throw CaseDataError(where + "[" + std::to_string(i) + "]: no numeric onset_s");
        Episode ep;
        ep.onset_s = e["onset_s"].get<double>();
        ep.end_s = optional_number(e, "end_s");
        ep.confirmed_s = optional_number(e, "detected_s");
        if (e.contains("type") && e["type"].is_string() && e.contains("region") &&
            e["region"].is_string())
            ep.label = e["type"].get<std::string>() + " " + e["region"].get<std::string>();
        out.push_back(ep);
    }
    return out;
}

ProcedureOutcome read_procedure(const Json& summary) {
    ProcedureOutcome p;
    if (!summary.contains("procedure") || !summary["procedure"].is_object()) return p;
    const Json& j = summary["procedure"];
    p.known = true;
    p.kind = j.value("kind", "");
    p.style = j.contains("style") && j["style"].is_string() ? j["style"].get<std::string>() : "";
    if (j.contains("cecum_reached") && j["cecum_reached"].is_boolean())
        p.cecum_reached = j["cecum_reached"].get<bool>();
    p.cecum_time_s = optional_number(j, "cecum_time_s");
    p.insertion_at_cecum_mm = optional_number(j, "insertion_at_cecum_mm");
    return p;
}

/// Keeps what came before `lost_s` (CaseRun::scope_through_wall_s).
static void cut_where_the_scope_went_through_the_wall(CaseRun& run, double lost_s) {
    const auto periods = static_cast<std::size_t>(
        std::lower_bound(run.time_s.begin(), run.time_s.end(), lost_s - 1e-9) - run.time_s.begin());
    const auto cut = [periods](auto& series) {
        if (series.size() > periods) series.resize(periods);
    };
    cut(run.time_s);
    cut(run.true_tip_path_mm);
    cut(run.true_max_station_force_N);
    cut(run.insertion_mm);
    cut(run.box_tip_path_mm);
    cut(run.box_model_tip_path_mm);
    cut(run.box_tip_uncertainty_mm);
    cut(run.box_max_contact_force_N);
    cut(run.box_model_max_contact_force_N);
    cut(run.box_self_lock);
    cut(run.box_model_self_lock);
    cut(run.box_contact_level);
    cut(run.box_model_contact_level);
    cut(run.box_fault_flags);
    cut(run.handle_force_N);
    cut(run.handle_torque_Nmm);
    cut(run.handle_insertion_mm);
    const auto samples = static_cast<std::size_t>(
        std::lower_bound(run.sample_time_s.begin(), run.sample_time_s.end(), lost_s - 1e-9) -
        run.sample_time_s.begin());
    run.sample_time_s.resize(std::min(samples, run.sample_time_s.size()));
    run.sample_force_N.resize(run.sample_time_s.size());
    run.sample_insertion_mm.resize(run.sample_time_s.size());
    for (std::vector<Episode>* list :
         {&run.loop_episodes, &run.warning_episodes, &run.critical_episodes}) {
        std::erase_if(*list, [lost_s](const Episode& e) { return e.onset_s >= lost_s; });
        for (Episode& e : *list)
            if (e.end_s && *e.end_s >= lost_s) e.end_s.reset();
    }
}

CaseRun read_case_run(const fs::path& folder) {
    CaseRun run;
    const fs::path summary_file = folder / "summary.json";
    if (!fs::is_regular_file(summary_file))
        throw CaseDataError(summary_file.string() +
                            ": missing (the case was not run, or its run was killed)");
    Json s;
    try {
        s = model::io::parse_json_file(summary_file.string());
    } catch (const std::exception& e) {
        throw CaseDataError(e.what());
    }
    if (!s.is_object()) throw CaseDataError(summary_file.string() + ": not a JSON object");
    run.status = s.value("status", "");
    run.message =
        s.contains("message") && s["message"].is_string() ? s["message"].get<std::string>() : "";
    run.duration_s = optional_number(s, "duration_s").value_or(0.0);
    run.wall_time_s = optional_number(s, "wall_time_s").value_or(0.0);
    run.procedure = read_procedure(s);
    if (run.status != "complete") return run;  // a failed run is listed, not scored
    if (!s.contains("truth") || !s["truth"].is_object())
        throw CaseDataError(summary_file.string() + ": no \"truth\" section");
    const Json& t = s["truth"];
    run.loop_episodes = read_episodes(t.value("loop_episodes", Json::array()),
                                      summary_file.string() + ": truth.loop_episodes");
    const Json forces = t.value("force_episodes", Json::object());
    run.warning_episodes =
        read_episodes(forces.value("warning_10N", Json::array()),
                      summary_file.string() + ": truth.force_episodes.warning_10N");
    run.critical_episodes =
        read_episodes(forces.value("critical_14N", Json::array()),
                      summary_file.string() + ": truth.force_episodes.critical_14N");

    const fs::path truth_file = folder / "truth.csv";
    // scope_beyond_wall_mm: runs before 2026-11-27 lack it (then nothing is cut).
    const bool beyond_wall = has_column(truth_file, "scope_beyond_wall_mm");
    std::vector<std::string> truth_columns{"time_s", "insertion_mm", "tip_path_mm",
                                           "max_station_force_N"};
    if (beyond_wall) truth_columns.emplace_back("scope_beyond_wall_mm");
    const Columns truth = read_columns(truth_file, truth_columns);
    const fs::path fw_file = folder / "firmware.csv";
    // tip_uncertainty_mm, model_tip_path_mm: written since the tip observer (2026-11-27).
    const bool observer = has_column(fw_file, "model_tip_path_mm");
    std::vector<std::string> fw_columns{
        "time_s",          "tip_path_mm",         "max_contact_force_N",
        "self_lock_alarm", "contact_force_level", "fault_flags"};
    if (observer) {
        fw_columns.emplace_back("tip_uncertainty_mm");
        fw_columns.emplace_back("model_tip_path_mm");
    }
    // model_max_contact_force_N: written since the contact force trees (2026-11-28); before
    // them the published largest force was the model's.
    const bool force_trees = has_column(fw_file, "model_max_contact_force_N");
    if (force_trees) fw_columns.emplace_back("model_max_contact_force_N");
    // model_self_lock_alarm: written since the loop alarm from evidence (2026-11-28); before it
    // the published alarm was the model's.
    const bool loop_alarm = has_column(fw_file, "model_self_lock_alarm");
    if (loop_alarm) fw_columns.emplace_back("model_self_lock_alarm");
    // model_contact_force_level: written since the contact-force level from evidence
    // (2026-11-30); before it the published level was the model's.
    const bool level_from_evidence = has_column(fw_file, "model_contact_force_level");
    if (level_from_evidence) fw_columns.emplace_back("model_contact_force_level");
    const Columns fw = read_columns(fw_file, fw_columns);
    if (truth.lines.size() != fw.lines.size())
        throw CaseDataError(truth_file.string() + " has " + std::to_string(truth.lines.size()) +
                            " rows, " + fw_file.string() + " " + std::to_string(fw.lines.size()) +
                            ": they must have one row per box period each");
    for (std::size_t r = 0; r < truth.lines.size(); ++r)
        if (truth.cells[0][r] != fw.cells[0][r])
            throw CaseDataError(truth_file.string() + ": line " + std::to_string(truth.lines[r]) +
                                ": time_s " + model::io::quote_text(truth.cells[0][r]) +
                                " is not " + fw_file.string() + "'s " +
                                model::io::quote_text(fw.cells[0][r]));
    run.time_s = numbers(truth, 0, truth_file, "time_s");
    run.insertion_mm = numbers(truth, 1, truth_file, "insertion_mm");
    run.true_tip_path_mm = numbers(truth, 2, truth_file, "tip_path_mm");
    run.true_max_station_force_N = numbers(truth, 3, truth_file, "max_station_force_N");
    run.box_tip_path_mm = numbers(fw, 1, fw_file, "tip_path_mm");
    run.box_max_contact_force_N = numbers(fw, 2, fw_file, "max_contact_force_N");
    run.box_self_lock = whole<std::uint8_t>(fw, 3, fw_file, "self_lock_alarm");
    run.box_contact_level = whole<std::uint8_t>(fw, 4, fw_file, "contact_force_level");
    run.box_fault_flags = whole<std::uint32_t>(fw, 5, fw_file, "fault_flags");
    if (observer) {
        run.box_tip_uncertainty_mm = numbers(fw, 6, fw_file, "tip_uncertainty_mm");
        run.box_model_tip_path_mm = numbers(fw, 7, fw_file, "model_tip_path_mm");
    } else {  // before the tip observer the published tip was the model's
        run.box_model_tip_path_mm = run.box_tip_path_mm;
    }
    const auto column = [&](const char* name) {
        return static_cast<std::size_t>(std::find(fw_columns.begin(), fw_columns.end(), name) -
                                        fw_columns.begin());
    };
    run.box_model_max_contact_force_N =
        force_trees
            ? numbers(fw, column("model_max_contact_force_N"), fw_file, "model_max_contact_force_N")
            : run.box_max_contact_force_N;
    run.box_model_self_lock = loop_alarm ? whole<std::uint8_t>(fw, column("model_self_lock_alarm"),
                                                               fw_file, "model_self_lock_alarm")
                                         : run.box_self_lock;
    run.box_model_contact_level = level_from_evidence
                                      ? whole<std::uint8_t>(fw, column("model_contact_force_level"),
                                                            fw_file, "model_contact_force_level")
                                      : run.box_contact_level;
    for (std::size_t k = 1; k < run.time_s.size(); ++k)
        if (!(run.time_s[k] > run.time_s[k - 1]))
            throw CaseDataError(truth_file.string() + ": line " + std::to_string(truth.lines[k]) +
                                ": time_s is not later than the line before");

    const fs::path rec_file = folder / "recording.csv";
    recording::Recording rec;
    try {
        rec = recording::RecordingReader().read_file(rec_file.string());
    } catch (const recording::RecordingError& e) {
        throw CaseDataError(rec_file.string() + ": " + e.what());
    }
    double force = kNaN, torque = kNaN, insertion = kNaN;
    double last_torque = kNaN;  // the torque of the last sample kept (sample_force_N's)
    std::size_t next = 0;
    run.handle_force_N.reserve(run.time_s.size());
    for (const recording::RecordingRow& row : rec.rows) {
        const double row_s = static_cast<double>(row.time_us) * 1e-6;
        if (row.handle) {
            force = row.handle->force_N;
            torque = row.handle->torque_Nmm;
        }
        if (row.insertion_roll) insertion = row.insertion_roll->insertion_mm;
        if (!row.handle && !row.insertion_roll) continue;
        while (next < run.time_s.size() && run.time_s[next] < row_s - 1e-9) {
            run.handle_force_N.push_back(run.sample_force_N.empty() ? kNaN
                                                                    : run.sample_force_N.back());
            run.handle_torque_Nmm.push_back(run.sample_force_N.empty() ? kNaN : last_torque);
            run.handle_insertion_mm.push_back(
                run.sample_insertion_mm.empty() ? kNaN : run.sample_insertion_mm.back());
            ++next;
        }
        run.sample_time_s.push_back(row_s);
        run.sample_force_N.push_back(force);
        run.sample_insertion_mm.push_back(insertion);
        last_torque = torque;
    }
    while (next < run.time_s.size()) {
        run.handle_force_N.push_back(run.sample_force_N.empty() ? kNaN : run.sample_force_N.back());
        run.handle_torque_Nmm.push_back(run.sample_force_N.empty() ? kNaN : last_torque);
        run.handle_insertion_mm.push_back(
            run.sample_insertion_mm.empty() ? kNaN : run.sample_insertion_mm.back());
        ++next;
    }
    if (beyond_wall) {
        const std::vector<double> beyond_mm = numbers(truth, 4, truth_file, "scope_beyond_wall_mm");
        for (std::size_t k = 0; k < beyond_mm.size(); ++k)
            if (beyond_mm[k] > model::truth::TruthReader::kThroughWall_mm) {
                run.scope_through_wall_s = run.time_s[k];
                cut_where_the_scope_went_through_the_wall(run, run.time_s[k]);
                break;
            }
    }
    return run;
}

}  // namespace scopekin::evaluate
