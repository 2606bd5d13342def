#include "host_sim/cli/batch_command.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "host_sim/cli/cli_support.hpp"
#include "host_sim/cli/run_command.hpp"
#include "host_sim/cli/shard.hpp"
#include "host_sim/cli/simulate_command.hpp"
#include "host_sim/recording/recording_format.hpp"
#include "model/model_error.hpp"

namespace scopekin::cli {
namespace {

using recording::csv_cell;

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

/// Columns of a shard summary (and of the merged one).
const char* const kSummaryHeader =
    "entry,shard,shards,kind,exit_status,status,duration_s,peak_handle_force_N,peak_estimated_"
    "contact_force_N,"
    "alarms,first_self_lock_s,flagged,folder,message";

struct BatchOptions {
    std::string manifest;
    std::string shard = "0/1";
    std::string out;
    std::uint64_t seed = 1;
    bool quiet = false;
};

struct MergeOptions {
    std::vector<std::string> summaries;
    std::string out;
};

std::string trim(const std::string& s) {
    const auto b = s.find_first_not_of(" \t\r");
    if (b == std::string::npos) return "";
    const auto e = s.find_last_not_of(" \t\r");
    return s.substr(b, e - b + 1);
}

/// A folder name for an entry: its file stem and 8 hex digits of its hash (two entries with the
/// same stem never share a folder).
std::string folder_name(const std::string& entry) {
    std::string stem = fs::path(entry).stem().string();
    for (char& c : stem)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_')) c = '_';
    char hash[16];
    std::snprintf(hash, sizeof hash, "%08llx",
                  static_cast<unsigned long long>(fnv1a(entry) & 0xffffffffULL));
    return stem + "-" + hash;
}

std::string number(const Json& j, const char* key) {
    if (!j.contains(key) || !j[key].is_number()) return "";
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.6g", j[key].get<double>());
    return buffer;
}

int run_batch(const BatchOptions& options) {
    std::size_t shard = 0, shards = 1;
    if (!parse_shard(options.shard, shard, shards)) {
        std::cerr << "scopekin batch: --shard " << options.shard
                  << ": expected I/N with 0 <= I < N (e.g. 0/4)\n";
        return 2;
    }
    std::ifstream in(options.manifest);
    if (!in) {
        std::cerr << "scopekin batch: cannot read " << options.manifest << "\n";
        return 2;
    }
    const fs::path base = fs::path(options.manifest).parent_path();
    std::vector<std::string> entries;
    std::set<std::string> seen;
    std::string line;
    std::size_t number_of_line = 0;
    while (std::getline(in, line)) {
        ++number_of_line;
        const std::string entry = trim(line);
        if (entry.empty() || entry[0] == '#') continue;
        const std::string ext = fs::path(entry).extension().string();
        if (ext != ".json" && ext != ".csv") {
            std::cerr << "scopekin batch: " << options.manifest << ": line " << number_of_line
                      << ": '" << entry
                      << "' is neither a scenario (.json) nor a recording (.csv)\n";
            return 2;
        }
        const fs::path path = fs::path(entry).is_absolute() ? fs::path(entry) : base / entry;
        if (!fs::is_regular_file(path)) {
            std::cerr << "scopekin batch: " << options.manifest << ": line " << number_of_line
                      << ": " << path.string() << " does not exist\n";
            return 2;
        }
        if (!seen.insert(entry).second) {
            std::cerr << "scopekin batch: " << options.manifest << ": line " << number_of_line
                      << ": '" << entry << "' is listed twice\n";
            return 2;
        }
        entries.push_back(entry);
    }
    if (entries.empty()) {
        std::cerr << "scopekin batch: " << options.manifest << " lists no scenario or recording\n";
        return 2;
    }
    std::vector<std::string> mine;
    for (const std::string& e : entries)
        if (shard_of(e, shards) == shard) mine.push_back(e);

    try {
        const fs::path dir(options.out);
        char name[64];
        std::snprintf(name, sizeof name, "summary_shard_%zu_of_%zu.csv", shard, shards);
        prepare_directory(dir,
                          {name});  // the old shard summary goes first; the new is renamed last
        PartFile summary(dir / name, dir / (std::string(name) + ".incomplete"));
        summary.stream() << kSummaryHeader << "\n";
        std::printf("shard %zu/%zu: %zu of the manifest's %zu entries\n", shard, shards,
                    mine.size(), entries.size());
        int worst = 0;
        for (std::size_t k = 0; k < mine.size(); ++k) {
            const std::string& entry = mine[k];
            const fs::path path = fs::path(entry).is_absolute() ? fs::path(entry) : base / entry;
            const fs::path folder = dir / folder_name(entry);
            const bool scenario = path.extension() == ".json";
            std::printf("[%zu/%zu] %s -> %s\n", k + 1, mine.size(), entry.c_str(),
                        folder.string().c_str());
            std::fflush(stdout);
            int status = 0;
            std::string message;
            try {
                if (scenario) {
                    SimulateOptions sim;
                    sim.scenario = path.string();
                    sim.out = folder.string();
                    sim.seed = options.seed;
                    sim.quiet = options.quiet;
                    status = run_simulate(sim);
                } else {
                    RunOptions run;
                    run.recording = path.string();
                    run.out = folder.string();
                    run.quiet = options.quiet;
                    status = run_recording(run);
                }
            } catch (const model::ModelError& e) {
                status = 2;
                message = e.what();
                std::cerr << "scopekin batch: " << entry << ": invalid: " << message << "\n";
            }
            Json s = Json::object();
            std::ifstream sj(folder / "summary.json");
            if (sj) s = Json::parse(sj, nullptr, false);
            if (s.is_discarded()) s = Json::object();
            std::string first_lock;
            std::size_t alarms = 0;
            if (s.contains("alarms") && s["alarms"].is_array()) {
                alarms = s["alarms"].size();
                for (const Json& a : s["alarms"])
                    if (a.value("kind", "") == "self_lock") {
                        first_lock = number(a, "raised_s");
                        break;
                    }
            }
            if (message.empty() && s.contains("message") && s["message"].is_string())
                message = s["message"].get<std::string>();
            const Json peak =
                s.contains("peak_handle_force_N") ? s["peak_handle_force_N"] : Json::object();
            const Json est = s.contains("peak_estimated_contact_force")
                                 ? s["peak_estimated_contact_force"]
                                 : Json::object();
            summary.stream() << csv_cell(entry) << ',' << shard << ',' << shards << ','
                             << (scenario ? "scenario" : "recording") << ',' << status << ','
                             << csv_cell(s.value("status", status == 0 ? "complete" : "failed"))
                             << ','
                             << (s.contains("duration_s") ? number(s, "duration_s")
                                                          : number(s, "last_time_s"))
                             << ',' << number(peak, "true") << ',' << number(est, "force_N") << ','
                             << alarms << ',' << first_lock << ','
                             << (s.value("flagged", false) ? 1 : 0) << ','
                             << csv_cell(folder.filename().string()) << ',' << csv_cell(message)
                             << '\n';
            worst = std::max(worst, status);
        }
        const fs::path written = summary.finish(true);
        std::printf("wrote %s\n", written.string().c_str());
        return worst;
    } catch (const OutputError& e) {
        std::cerr << "scopekin batch: " << e.what() << "\n";
        return 3;
    }
}

int run_merge(const MergeOptions& options) {
    std::map<std::string, std::string> rows;  // entry -> line (sorted by entry)
    std::set<std::size_t> shards_seen;
    std::size_t shard_count = 0;
    for (const std::string& file : options.summaries) {
        std::ifstream in(file);
        if (!in) {
            std::cerr << "scopekin batch-merge: cannot read " << file << "\n";
            return 2;
        }
        std::string line;
        std::getline(in, line);
        if (trim(line) != kSummaryHeader) {
            std::cerr << "scopekin batch-merge: " << file
                      << ": line 1 is not a batch summary header\n";
            return 2;
        }
        std::size_t number_of_line = 1;
        while (std::getline(in, line)) {
            ++number_of_line;
            if (trim(line).empty()) continue;
            std::stringstream cells(line);
            std::string entry, shard_text, shards_text;
            std::getline(cells, entry, ',');
            std::getline(cells, shard_text, ',');
            std::getline(cells, shards_text, ',');
            std::size_t shard = 0, shards = 0;
            if (!parse_shard(shard_text + "/" + shards_text, shard, shards)) {
                std::cerr << "scopekin batch-merge: " << file << ": line " << number_of_line
                          << ": bad shard " << shard_text << "/" << shards_text << "\n";
                return 2;
            }
            if (shard_count != 0 && shards != shard_count) {
                std::cerr << "scopekin batch-merge: " << file << ": line " << number_of_line
                          << ": shard of " << shards << " where the others are of " << shard_count
                          << "\n";
                return 2;
            }
            shard_count = shards;
            shards_seen.insert(shard);
            if (!rows.emplace(entry, line).second) {
                std::cerr << "scopekin batch-merge: " << file << ": line " << number_of_line << ": "
                          << entry << " appears twice (the same shard merged twice?)\n";
                return 2;
            }
        }
    }
    try {
        PartFile merged{fs::path(options.out)};
        merged.stream() << kSummaryHeader << "\n";
        for (const auto& [entry, line] : rows)
            merged.stream() << line << "\n";
        merged.finish(true);
    } catch (const OutputError& e) {
        std::cerr << "scopekin batch-merge: " << e.what() << "\n";
        return 3;
    }
    std::vector<std::size_t> missing;
    for (std::size_t i = 0; i < shard_count; ++i)
        if (shards_seen.count(i) == 0) missing.push_back(i);
    std::printf("merged %zu entries from %zu summaries into %s\n", rows.size(),
                options.summaries.size(), options.out.c_str());
    if (!missing.empty()) {
        std::string list;
        for (std::size_t i : missing)
            list += (list.empty() ? "" : ", ") + std::to_string(i);
        std::cerr << "scopekin batch-merge: shards missing (or with no entries): " << list << " of "
                  << shard_count << "\n";
    }
    return 0;
}

}  // namespace

void add_batch_commands(CLI::App& app) {
    auto options = std::make_shared<BatchOptions>();
    CLI::App* cmd =
        app.add_subcommand("batch",
                           "Run the scenarios (.json: as `simulate`) and recordings (.csv: as "
                           "`run`) listed in MANIFEST (one path per "
                           "line, relative to the manifest; '#' starts a comment) that fall in "
                           "shard I of N: an entry belongs to shard "
                           "FNV-1a-64(entry as written) mod N, so the assignment depends on the "
                           "entry alone. Each entry gets its own "
                           "folder in DIR; DIR/summary_shard_I_of_N.csv has one row per entry. Run "
                           "the N shards as an array job "
                           "(host_sim/README.md, 'Batch runs on a cluster': Slurm, Kubernetes) and "
                           "combine them with `scopekin batch-merge`. Exit status: the "
                           "worst of the entries' (0 all done, 1 a run failed, 2 invalid "
                           "manifest/entry, 3 an output cannot be "
                           "written).");
    cmd->add_option("manifest", options->manifest, "Manifest file")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--shard", options->shard, "I/N: this job's shard (0-based) of N")
        ->default_val("0/1");
    cmd->add_option("--out", options->out, "Output directory")->required();
    cmd->add_option("--seed", options->seed,
                    "Seed of the sensor models for the scenarios (0 .. 2^64-1)")
        ->default_val(1)
        ->check(whole_number());
    cmd->add_flag("--quiet", options->quiet, "No progress bars");
    cmd->callback([options]() { throw CLI::RuntimeError(run_batch(*options)); });

    auto merge = std::make_shared<MergeOptions>();
    CLI::App* m = app.add_subcommand("batch-merge",
                                     "Combine shard summaries (summary_shard_I_of_N.csv) into one "
                                     "CSV sorted by entry; refuses a file that is not a "
                                     "shard summary, shards of different N, or an entry twice, and "
                                     "names shards that are missing.");
    m->add_option("summaries", merge->summaries, "Shard summary CSV files")
        ->required()
        ->check(CLI::ExistingFile);
    m->add_option("--out", merge->out, "Merged CSV")->required();
    m->callback([merge]() { throw CLI::RuntimeError(run_merge(*merge)); });
}

}  // namespace scopekin::cli
