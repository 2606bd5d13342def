#include "host_sim/cli/evaluate_command.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "host_sim/cli/cli_support.hpp"
#include "host_sim/cli/shard.hpp"
#include "host_sim/evaluate/case_run.hpp"
#include "host_sim/evaluate/estimators.hpp"
#include "host_sim/evaluate/force_monitor.hpp"
#include "host_sim/evaluate/manifest.hpp"
#include "host_sim/evaluate/scorecard.hpp"
#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"

extern char** environ;

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

struct EvaluateOptions {
    std::string manifest;
    std::string out;
    std::string shard = "0/1";
    int jobs = 1;
    std::string thresholds = SCOPEKIN_FORCE_MONITOR_THRESHOLDS;
    bool quiet = false;
    bool score_only = false;
    bool list = false;
    bool plots = true;
};

struct MergeOptions {
    std::vector<std::string> shards;
    std::string out;
    bool plots = true;
};

struct TuneOptions {
    std::vector<std::string> dirs;
    std::string out;
    double max_false_per_10min = 3.0;
};

std::string shard_file_name(std::size_t shard, std::size_t shards) {
    return "scorecard_shard_" + std::to_string(shard) + "_of_" + std::to_string(shards) + ".json";
}

/// A child `scopekin simulate` with stdout and stderr in a log file.
struct Child {
    pid_t pid = 0;
    std::size_t index = 0;  ///< into the shard's cases
    std::chrono::steady_clock::time_point start;
};

pid_t start_simulate(const std::string& exe, const fs::path& folder, std::uint64_t seed,
                     std::string& error) {
    const std::vector<std::string> argv = {exe,
                                           "simulate",
                                           (folder / "scenario.json").string(),
                                           "--out",
                                           folder.string(),
                                           "--seed",
                                           std::to_string(seed),
                                           "--quiet"};
    std::vector<char*> args;
    for (const std::string& a : argv)
        args.push_back(const_cast<char*>(a.c_str()));  // posix_spawn's signature; not written
    args.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    const std::string log = (folder / "simulate.log").string();
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    std::fflush(stdout);
    std::fflush(stderr);
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, exe.c_str(), &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) {
        error = exe + ": " + std::strerror(spawned);
        return 0;
    }
    return pid;
}

std::string describe_status(int status) {
    if (WIFEXITED(status)) return "exit " + std::to_string(WEXITSTATUS(status));
    if (WIFSIGNALED(status))
        return "ended by signal " + std::to_string(WTERMSIG(status)) + " (" +
               strsignal(WTERMSIG(status)) + ")";
    return "ended";
}

/// Runs the cases' simulations, `jobs` at once; returns per case the child's end ("exit 0", ...).
std::vector<std::string> run_cases(const std::vector<const evaluate::ManifestCase*>& cases,
                                   const fs::path& dir, int jobs, bool quiet) {
    const std::string exe = fs::read_symlink("/proc/self/exe").string();
    std::vector<std::string> ended(cases.size());
    std::vector<Child> running;
    std::size_t next = 0, done = 0;
    const auto start = std::chrono::steady_clock::now();
    while (done < cases.size()) {
        while (running.size() < static_cast<std::size_t>(jobs) && next < cases.size()) {
            const evaluate::ManifestCase& c = *cases[next];
            const fs::path folder = dir / "cases" / c.name;
            fs::create_directories(folder);
            write_json(folder / "scenario.json", Json(c.scenario));
            std::string error;
            const pid_t pid = start_simulate(exe, folder, c.sensor_seed, error);
            if (pid == 0) {
                ended[next] = "could not be started: " + error;
                ++done;
                std::cerr << "evaluate: " << c.name << ": " << ended[next] << "\n";
            } else {
                running.push_back({pid, next, std::chrono::steady_clock::now()});
            }
            ++next;
        }
        if (running.empty()) continue;
        int status = 0;
        const pid_t pid = waitpid(-1, &status, 0);
        if (pid < 0) {
            if (errno == EINTR) continue;
            throw OutputError(std::string("waiting for the simulations: ") + std::strerror(errno));
        }
        for (std::size_t r = 0; r < running.size(); ++r) {
            if (running[r].pid != pid) continue;
            const Child child = running[r];
            running.erase(running.begin() + static_cast<std::ptrdiff_t>(r));
            ended[child.index] = describe_status(status);
            ++done;
            if (!quiet) {
                const double wall =
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - child.start)
                        .count();
                const double total =
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
                std::fprintf(stderr, "evaluate: [%zu/%zu] %s: %s, %.1f s wall (%.0f s so far)\n",
                             done, cases.size(), cases[child.index]->name.c_str(),
                             ended[child.index].c_str(), wall, total);
            }
            break;
        }
    }
    return ended;
}

/// Scores one case folder and writes its score.json and estimates.csv.
Json score_folder(const evaluate::ManifestCase& c, const fs::path& dir,
                  const evaluate::EstimatorContext& context, const std::string& ended) {
    const fs::path folder = dir / "cases" / c.name;
    const std::string relative = (fs::path("cases") / c.name).string();
    Json score;
    if (!fs::is_regular_file(folder / "summary.json")) {
        std::string message = "no summary.json in " + folder.string();
        if (!ended.empty()) message += " (the simulation " + ended + "; see simulate.log)";
        score = evaluate::unscored_case(c.name, c.style, relative, "not_run", message);
    } else {
        try {
            const evaluate::CaseRun run = evaluate::read_case_run(folder);
            std::vector<evaluate::EstimatorOutput> outputs;
            if (run.status == "complete") {
                outputs = evaluate::estimator_outputs(run, context);
                PartFile estimates(folder / "estimates.csv");
                estimates.stream() << evaluate::estimates_csv(run, outputs);
                estimates.finish(true);
            }
            score = evaluate::score_case(c.name, c.style, relative, run, outputs);
        } catch (const evaluate::CaseDataError& e) {
            score = evaluate::unscored_case(c.name, c.style, relative, "unscorable", e.what());
        }
    }
    score["sensor_seed"] = c.sensor_seed;
    write_json(folder / "score.json", score);
    return score;
}

/// scorecard.json, .csv, .md and the plots from the case scores of a whole manifest.
void write_overall(const fs::path& dir, const Json& header, const std::vector<Json>& cases,
                   bool plots) {
    const Json overall = evaluate::aggregate(cases);
    PartFile csv(dir / "scorecard.csv");
    csv.stream() << evaluate::scorecard_csv_header() << "\n";
    for (const Json& c : cases)
        for (const std::string& row : evaluate::scorecard_csv_rows(c))
            csv.stream() << row << "\n";
    csv.finish(true);
    const std::string md = evaluate::scorecard_markdown(overall, header.value("manifest", ""),
                                                        header.value("description", ""));
    PartFile markdown(dir / "scorecard.md");
    markdown.stream() << md;
    markdown.finish(true);
    Json scorecard = header;
    scorecard["overall"] = overall;
    scorecard["cases"] = cases;
    // Plots before the summary (scorecard.json) is renamed: a folder with scorecard.json is
    // finished.
    const fs::path part = write_json_part(dir / "scorecard.json", scorecard);
    if (plots) {
        const ProgramResult r = run_program({SCOPEKIN_PYTHON, SCOPEKIN_EVALUATION_PLOT_SCRIPT,
                                             fs::absolute(dir).string(), "--scorecard",
                                             fs::absolute(part).string(), "--quiet"});
        if (!r.ok())
            std::cerr << "scopekin evaluate: warning: the plots were not drawn: plot_evaluation.py "
                      << r.describe() << "\n";
    }
    commit_part(dir / "scorecard.json");
    std::printf("%s\n", md.c_str());
}

int run_evaluate(const EvaluateOptions& options) {
    std::size_t shard = 0, shards = 1;
    if (!parse_shard(options.shard, shard, shards)) {
        std::cerr << "scopekin evaluate: --shard " << model::io::quote_text(options.shard)
                  << ": expected I/N with 0 <= I < N (e.g. 0/4)\n";
        return 2;
    }
    if (options.jobs < 1 || options.jobs > 64) {
        std::cerr << "scopekin evaluate: --jobs " << options.jobs << ": expected 1 to 64\n";
        return 2;
    }
    if (!options.list && options.out.empty()) {
        std::cerr << "scopekin evaluate: --out DIR is required (except with --list)\n";
        return 2;
    }
    evaluate::Manifest manifest;
    evaluate::EstimatorContext context;
    try {
        manifest = evaluate::read_manifest(options.manifest);
        context.force_monitor = evaluate::read_force_monitor_thresholds(options.thresholds);
    } catch (const model::ModelError& e) {
        std::cerr << "scopekin evaluate: " << e.what() << "\n";
        return 2;
    }
    std::vector<const evaluate::ManifestCase*> mine;
    for (const evaluate::ManifestCase& c : manifest.cases)
        if (shard_of(c.name, shards) == shard) mine.push_back(&c);
    std::printf("evaluate %s ('%s'): shard %zu/%zu: %zu of its %zu cases\n",
                options.manifest.c_str(), manifest.name.c_str(), shard, shards, mine.size(),
                manifest.cases.size());
    if (options.list) {
        for (const evaluate::ManifestCase* c : mine)
            std::printf("  %s  (%s, sensor seed %llu)\n", c->name.c_str(), c->style.c_str(),
                        static_cast<unsigned long long>(c->sensor_seed));
        return 0;
    }
    try {
        const fs::path dir(options.out);
        const std::string shard_name = shard_file_name(shard, shards);
        if (shards == 1)
            prepare_directory(
                dir, {"scorecard.json", shard_name.c_str(), "scorecard.csv", "scorecard.md",
                      "distributions.png", "worst_cases.png", "procedures.png"});
        else
            prepare_directory(dir, {shard_name.c_str()});
        const auto start = std::chrono::steady_clock::now();
        std::vector<std::string> ended(mine.size());
        if (!options.score_only) {
            // The old scores of the cases go first: a case folder with a score.json is scored.
            for (const evaluate::ManifestCase* c : mine) {
                std::error_code ec;
                fs::remove(dir / "cases" / c->name / "score.json", ec);
                fs::remove(dir / "cases" / c->name / "estimates.csv", ec);
            }
            ended = run_cases(mine, dir, options.jobs, options.quiet);
        }
        const double run_wall =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::vector<Json> scores;
        int status = 0;
        double simulated = 0;
        for (std::size_t i = 0; i < mine.size(); ++i) {
            Json s = score_folder(*mine[i], dir, context, ended[i]);
            if (s.value("status", "") != "complete") {
                status = 1;
                std::cerr << "scopekin evaluate: " << mine[i]->name << ": " << s.value("status", "")
                          << ": " << s.value("message", "") << "\n";
            } else {
                simulated += s.value("duration_s", 0.0);
            }
            scores.push_back(std::move(s));
        }
        Json header;
        header["manifest"] = manifest.name;
        header["manifest_file"] = options.manifest;
        header["description"] = manifest.description;
        header["thresholds_file"] = options.thresholds;
        header["thresholds"] = {{"loop_force_N", context.force_monitor.loop_force_N},
                                {"loop_rate_N_per_s", context.force_monitor.loop_rate_N_per_s},
                                {"warning_N", context.force_monitor.warning_N},
                                {"critical_N", context.force_monitor.critical_N}};
        for (auto& [key, value] : header["thresholds"].items())
            if (!std::isfinite(value.get<double>())) value = nullptr;
        header["cases_in_manifest"] = manifest.cases.size();
        header["shard"] = shard;
        header["shards"] = shards;
        header["run"] = {
            {"jobs", options.jobs},
            {"score_only", options.score_only},
            {"wall_s", run_wall},
            {"simulated_s", simulated},
            {"simulated_s_per_wall_s",
             run_wall > 0 && !options.score_only ? Json(simulated / run_wall) : Json()}};
        Json shard_json = header;
        shard_json["cases"] = scores;
        if (shards == 1) {
            write_json(dir / shard_name, shard_json);
            write_overall(dir, header, scores, options.plots);
        } else {
            write_json(dir / shard_name, shard_json);
            std::printf("wrote %s (combine the shards with `scopekin evaluate-merge`)\n",
                        (dir / shard_name).string().c_str());
        }
        if (!options.score_only)
            std::printf(
                "%zu cases: %.1f s simulated in %.1f s wall with %d job(s): %.2f s "
                "simulated per wall second\n",
                mine.size(), simulated, run_wall, options.jobs,
                run_wall > 0 ? simulated / run_wall : 0.0);
        return status;
    } catch (const OutputError& e) {
        std::cerr << "scopekin evaluate: " << e.what() << "\n";
        return 3;
    } catch (const fs::filesystem_error& e) {
        std::cerr << "scopekin evaluate: " << e.what() << "\n";
        return 3;
    }
}

int run_merge(const MergeOptions& options) {
    std::vector<Json> cases;
    std::set<std::string> names;
    std::set<std::size_t> seen;
    std::size_t shards = 0, in_manifest = 0;
    Json header;
    double wall = 0, simulated = 0;
    const fs::path out(options.out);
    for (const std::string& file : options.shards) {
        nlohmann::json j;
        try {
            j = model::io::parse_json_file(file);
        } catch (const model::ModelError& e) {
            std::cerr << "scopekin evaluate-merge: " << e.what() << "\n";
            return 2;
        }
        if (!j.is_object() || !j.contains("shards") || !j["shards"].is_number_unsigned() ||
            !j.contains("shard") || !j["shard"].is_number_unsigned() || !j.contains("cases") ||
            !j["cases"].is_array() || !j.contains("manifest") || !j["manifest"].is_string()) {
            std::cerr << "scopekin evaluate-merge: " << file
                      << ": not a scorecard shard (scorecard_shard_I_of_N.json)\n";
            return 2;
        }
        const auto n = j["shards"].get<std::size_t>();
        const auto i = j["shard"].get<std::size_t>();
        if (shards == 0) {
            shards = n;
            header["manifest"] = j["manifest"];
            header["manifest_file"] = j.value("manifest_file", "");
            header["description"] = j.value("description", "");
            header["thresholds_file"] = j.value("thresholds_file", "");
            header["thresholds"] = j.value("thresholds", nlohmann::json::object());
            in_manifest = j.value("cases_in_manifest", std::size_t{0});
        } else if (n != shards || j["manifest"] != header["manifest"]) {
            std::cerr << "scopekin evaluate-merge: " << file << ": shard " << i << "/" << n
                      << " of '" << j["manifest"].get<std::string>() << "', the others are of "
                      << shards << " shards of '" << header["manifest"].get<std::string>() << "'\n";
            return 2;
        }
        if (i >= n || !seen.insert(i).second) {
            std::cerr << "scopekin evaluate-merge: " << file << ": shard " << i << "/" << n
                      << " given twice (or out of range)\n";
            return 2;
        }
        if (j.contains("run") && j["run"].is_object()) {
            wall += j["run"].value("wall_s", 0.0);
            simulated += j["run"].value("simulated_s", 0.0);
        }
        const fs::path base = fs::path(file).parent_path();
        for (const nlohmann::json& c : j["cases"]) {
            Json oc = c;
            const std::string name = c.value("case", "");
            if (!names.insert(name).second) {
                std::cerr << "scopekin evaluate-merge: " << file << ": case '" << name
                          << "' appears twice\n";
                return 2;
            }
            // The folder relative to the merged scorecard's directory.
            const fs::path folder = fs::absolute(base / c.value("folder", ""));
            oc["folder"] = fs::relative(folder, fs::absolute(out)).string();
            cases.push_back(oc);
        }
    }
    std::sort(cases.begin(), cases.end(), [](const Json& a, const Json& b) {
        return a.value("case", "") < b.value("case", "");
    });
    std::vector<std::size_t> missing;
    for (std::size_t i = 0; i < shards; ++i)
        if (seen.count(i) == 0) missing.push_back(i);
    header["cases_in_manifest"] = in_manifest;
    header["shard"] = 0;
    header["shards"] = 1;
    header["merged_from"] = options.shards;
    header["run"] = {{"wall_s_summed_over_shards", wall}, {"simulated_s", simulated}};
    try {
        prepare_directory(out, {"scorecard.json", "scorecard.csv", "scorecard.md",
                                "distributions.png", "worst_cases.png", "procedures.png"});
        write_overall(out, header, cases, options.plots);
    } catch (const OutputError& e) {
        std::cerr << "scopekin evaluate-merge: " << e.what() << "\n";
        return 3;
    }
    int status = 0;
    if (!missing.empty()) {
        std::string list;
        for (std::size_t i : missing)
            list += (list.empty() ? "" : ", ") + std::to_string(i);
        std::cerr << "scopekin evaluate-merge: shards missing: " << list << " of " << shards
                  << ": the scorecard covers " << cases.size() << " of " << in_manifest
                  << " cases\n";
        status = 1;
    } else if (in_manifest != 0 && cases.size() != in_manifest) {
        std::cerr << "scopekin evaluate-merge: the shards hold " << cases.size() << " of "
                  << in_manifest << " cases\n";
        status = 1;
    }
    std::printf("merged %zu cases from %zu shard(s) into %s\n", cases.size(), options.shards.size(),
                options.out.c_str());
    return status;
}

/// The complete cases of one evaluated set (DIR/scorecard.json) appended to `cases`, and the set's
/// manifest name; false (the message printed) for a set that cannot be tuned on.
bool read_tuning_set(const fs::path& dir, std::vector<evaluate::TuningCase>& cases,
                     std::string& manifest) {
    nlohmann::json scorecard;
    try {
        scorecard = model::io::parse_json_file((dir / "scorecard.json").string());
    } catch (const model::ModelError& e) {
        std::cerr << "scopekin evaluate-tune: " << e.what()
                  << " (give the --out DIR of `scopekin evaluate` on the development set, or "
                     "of `scopekin evaluate-merge`)\n";
        return false;
    }
    manifest = scorecard.value("manifest", "");
    if (manifest.find("validation") != std::string::npos) {
        std::cerr << "scopekin evaluate-tune: " << (dir / "scorecard.json").string()
                  << ": the set is '" << manifest
                  << "': the validation set is never tuned on (tune on the development set)\n";
        return false;
    }
    for (const nlohmann::json& c : scorecard.value("cases", nlohmann::json::array())) {
        if (c.value("status", "") != "complete") continue;
        const fs::path folder = dir / c.value("folder", "");
        try {
            const evaluate::CaseRun run = evaluate::read_case_run(folder);
            if (run.status != "complete") continue;
            cases.push_back({c.value("case", ""), evaluate::force_monitor_features(run),
                             run.loop_episodes, run.warning_episodes, run.critical_episodes});
        } catch (const evaluate::CaseDataError& e) {
            std::cerr << "scopekin evaluate-tune: " << e.what() << "\n";
            return false;
        }
    }
    return true;
}

int run_tune(const TuneOptions& options) {
    if (!(options.max_false_per_10min >= 0) || !std::isfinite(options.max_false_per_10min)) {
        std::cerr << "scopekin evaluate-tune: --max-false-per-10min must be a finite number >= "
                     "0\n";
        return 2;
    }
    std::vector<evaluate::TuningCase> cases;
    std::string manifest;
    std::string dirs;
    for (const std::string& dir : options.dirs) {
        std::string set;
        if (!read_tuning_set(fs::path(dir), cases, set)) return 2;
        manifest += (manifest.empty() ? "" : "+") + set;
        dirs += (dirs.empty() ? "" : " ") + dir;
    }
    if (cases.empty()) {
        std::cerr << "scopekin evaluate-tune: " << dirs << " holds no complete case\n";
        return 2;
    }
    std::set<std::string> names;
    for (const evaluate::TuningCase& c : cases) {
        if (!names.insert(c.name).second) {
            std::cerr << "scopekin evaluate-tune: case '" << c.name
                      << "' is given twice (a set given twice, or two sets that share a case)\n";
            return 2;
        }
    }
    Json tuned = evaluate::tune_force_monitor(cases, options.max_false_per_10min, manifest);
    tuned["command"] = "scopekin evaluate-tune " + dirs + " --out " + options.out +
                       " --max-false-per-10min " + std::to_string(options.max_false_per_10min);
    try {
        write_json(options.out, tuned);
    } catch (const OutputError& e) {
        std::cerr << "scopekin evaluate-tune: " << e.what() << "\n";
        return 3;
    }
    std::printf(
        "tuned on %zu cases of '%s': loop %s N / %s N/s, warning %s N, critical %s N\n"
        "wrote %s\n",
        cases.size(), manifest.c_str(), tuned["loop"]["force_N"].dump().c_str(),
        tuned["loop"]["rate_N_per_s"].dump().c_str(), tuned["warning"]["force_N"].dump().c_str(),
        tuned["critical"]["force_N"].dump().c_str(), options.out.c_str());
    return 0;
}

}  // namespace

void add_evaluate_commands(CLI::App& app) {
    auto options = std::make_shared<EvaluateOptions>();
    CLI::App* cmd = app.add_subcommand(
        "evaluate",
        "Score the box's estimators on the cases of MANIFEST (host_sim/evaluate/README.md): each "
        "case (a patient, a physician or procedure, a sensor seed) runs as `scopekin simulate` "
        "does, with the firmware in the loop, into DIR/cases/NAME (scenario.json, simulate.log, "
        "the run's files), then every estimator (the box: its published tip, largest contact "
        "force and alarms, firmware/README.md; the baselines: the depth replay's, the handle force "
        "monitor and the insertion depth as the tip) is scored against truth.csv: tip position "
        "error, the tip within its stated uncertainty, largest "
        "contact force error, loop and contact force alarms against the true episodes "
        "(detected within 0.5 s, latency, missed, false alarms per 10 min, time up after the "
        "end), fault flag shares. Writes DIR/cases/NAME/score.json and estimates.csv, "
        "DIR/scorecard_shard_I_of_N.json and, unsharded, DIR/scorecard.json, scorecard.csv (one "
        "row per case x estimator), scorecard.md (the table, also printed) and two PNGs (a third, "
        "procedures.png, the insertion at cecal intubation per style, when the set has physician "
        "cases). A case "
        "belongs to shard FNV-1a-64(its name) mod N; combine shards with `scopekin "
        "evaluate-merge`. Exit status 0 every case ran and was scored, 1 a case failed or could "
        "not be scored (listed in the scorecard), 2 invalid manifest or option (nothing run), 3 "
        "an output cannot be written.");
    cmd->add_option("manifest", options->manifest, "Manifest JSON file")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("--out", options->out,
                    "Output directory (created if missing; the shard's old scorecard is removed "
                    "first)");
    cmd->add_option("--shard", options->shard, "I/N: this job's shard (0-based) of N")
        ->default_val("0/1");
    cmd->add_option("--jobs", options->jobs,
                    "Cases simulated at once, each in its own process (the firmware keeps "
                    "static state: no threads); 1 to 64")
        ->default_val(1);
    cmd->add_option("--thresholds", options->thresholds,
                    "The handle force monitor's thresholds (default: the committed "
                    "host_sim/evaluate/force_monitor_thresholds.json)")
        ->check(CLI::ExistingFile);
    cmd->add_flag("--score-only", options->score_only,
                  "Do not run: score the case folders already in DIR (after changing a scoring "
                  "rule or the thresholds)");
    cmd->add_flag("--list", options->list,
                  "Check the manifest and list the shard's cases; run nothing");
    cmd->add_flag(
        "--no-plots", [options](std::int64_t) { options->plots = false; }, "Do not draw the PNGs");
    cmd->add_flag("--quiet", options->quiet, "No progress on stderr");
    cmd->callback([options]() { throw CLI::RuntimeError(run_evaluate(*options)); });

    auto merge = std::make_shared<MergeOptions>();
    CLI::App* m = app.add_subcommand(
        "evaluate-merge",
        "Combine the shards of `scopekin evaluate` (DIR/scorecard_shard_I_of_N.json) into one "
        "scorecard in DIR (scorecard.json, .csv, .md, PNGs). Refuses a file that is not a shard, "
        "shards of different N or manifests, a shard or a case given twice (exit 2); names "
        "missing shards and exits 1 if the scorecard does not cover the whole manifest.");
    m->add_option("shards", merge->shards, "Shard scorecards (scorecard_shard_I_of_N.json)")
        ->required()
        ->check(CLI::ExistingFile);
    m->add_option("--out", merge->out, "Output directory of the merged scorecard")->required();
    m->add_flag(
        "--no-plots", [merge](std::int64_t) { merge->plots = false; }, "Do not draw the PNGs");
    m->callback([merge]() { throw CLI::RuntimeError(run_merge(*merge)); });

    auto tune = std::make_shared<TuneOptions>();
    CLI::App* t = app.add_subcommand(
        "evaluate-tune",
        "Tune the handle force monitor baseline's thresholds on evaluated DEVELOPMENT sets "
        "(DIR...: the --out of `scopekin evaluate` or `evaluate-merge`, their cases pooled; a set "
        "named 'validation' is refused): per alarm, a grid search for the most true episodes "
        "detected within 0.5 s with at most --max-false-per-10min false alarms per 10 minutes, "
        "pooled over the cases "
        "(host_sim/evaluate/README.md). Writes the thresholds file `scopekin evaluate` reads.");
    t->add_option("dirs", tune->dirs,
                  "Evaluated development sets, one or more (e.g. development and "
                  "development_extra); their complete cases are pooled")
        ->required();
    t->add_option("--out", tune->out,
                  "Thresholds file (e.g. host_sim/evaluate/force_monitor_thresholds.json)")
        ->required();
    t->add_option("--max-false-per-10min", tune->max_false_per_10min,
                  "The false alarm budget of the objective (pooled, per 10 minutes)")
        ->default_val(3.0);
    t->callback([tune]() { throw CLI::RuntimeError(run_tune(*tune)); });
}

}  // namespace scopekin::cli
