#include "host_sim/cli/discrepancy_command.hpp"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "host_sim/cli/cli_support.hpp"
#include "host_sim/discrepancy/static_cantilever.hpp"
#include "host_sim/discrepancy/workflow.hpp"
#include "host_sim/recording/recording_reader.hpp"
#include "model/io/strict_json.hpp"
#include "model/model_error.hpp"

namespace scopekin::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

struct DiscrepancyOptions {
    std::string recording;
    std::string model;
    std::string out;
    unsigned threads = 2;
    double max_gap_s = recording::kDefaultMaxGap_s;
    double fit_budget_s = discrepancy::kDefaultFitBudget_s;
    bool quiet = false;
    bool plots = true;
    bool thesis_cantilever = false;
    bool compare_only = false;
};

/// The static real-data case (host_sim/discrepancy/README.md): report.json and report.md.
int run_thesis_cantilever_case(const DiscrepancyOptions& o) {
    try {
        const fs::path dir(o.out);
        prepare_directory(dir, {"report.json", "report.md"});
        if (!o.quiet)
            std::fprintf(
                stderr,
                "fitting the four candidates, each also nine times with one point left out ...\n");
        const discrepancy::CantileverReport r = discrepancy::run_thesis_cantilever();
        PartFile md(dir / "report.md");
        md.stream() << r.markdown;
        md.finish(true);
        write_json(dir / "report.json", r.json);  // last of all
        std::printf("%s", r.markdown.c_str());
        std::printf("wrote report.json, report.md into %s\n", dir.string().c_str());
        return 0;
    } catch (const OutputError& e) {
        std::cerr << "scopekin discrepancy: " << e.what() << "\n";
        return 3;
    }
}

/// "ei_profile (tip_factor 0.909, handle_factor 0.926)": a candidate set and its fitted values.
std::string fitted_set_text(const Json& set) {
    std::string text;
    for (std::size_t k = 0; k < set["effects"].size(); ++k) {
        std::string values;
        for (const Json& p : set["parameters"][k]) {
            if (!p["fitted"].get<bool>()) continue;
            char v[64];
            if (p["value"].is_number())
                std::snprintf(v, sizeof v, "%.4g", p["value"].get<double>());
            else
                std::snprintf(v, sizeof v, "%s", p["value"].dump().c_str());
            values += (values.empty() ? "" : ", ") + p["name"].get<std::string>() + " " + v;
        }
        text += (text.empty() ? "" : " + ") + set["effects"][k].get<std::string>() + " (" + values +
                ")";
    }
    return text;
}

/// report.md's section on the candidates the recording cannot tell from the named set.
std::string equally_consistent_markdown(const Json& r) {
    if (!r.contains("equally_consistent") || r["equally_consistent"]["sets"].empty()) return "";
    std::string md = "## Explained as well by\n\n";
    for (const Json& set : r["equally_consistent"]["sets"]) {
        char cost[32];
        std::snprintf(cost, sizeof cost, "%.4g", set["held_out_cost"].get<double>());
        md += "- " + fitted_set_text(set) + ": held-out cost " + cost + "\n";
    }
    return md + "\nThis recording cannot tell these from the effects named (" +
           r["equally_consistent"]["rule"].get<std::string>() +
           "); a recording that loads the scope differently may.\n\n";
}

/// report.md: the verdict, the effects, the errors before and after, the candidates' scores.
std::string report_markdown(const Json& r) {
    auto num = [](const Json& v, const char* format) {
        if (!v.is_number()) return std::string("–");
        char text[64];
        std::snprintf(text, sizeof text, format, v.get<double>());
        return std::string(text);
    };
    std::string md = "# Discrepancy report\n\n";
    md += "- recording: `" + r["recording"].get<std::string>() + "`\n";
    md += "- model: " + r["model"].get<std::string>() + "\n";
    md += "- **verdict: " + r["verdict"].get<std::string>() + "**\n";
    md += "- model runs: " + std::to_string(r["model_runs"].get<std::size_t>()) + " (" +
          num(r["simulated_s"], "%.0f") + " recording seconds simulated), " +
          num(r["wall_time_s"], "%.1f") + " s\n";
    if (r.contains("predictability") && r["predictability"]["judged_again"].get<bool>())
        md += "- **judged up to " + num(r["predictability"]["until_s"], "%.2f") +
              " s of the recording only** (`predictability` in report.json): the model run with "
              "the drive moved by half an encoder count either way parts there, so the record "
              "cannot decide what follows; the first pass over all of it was " +
              r["predictability"]["first_pass"]["verdict"].get<std::string>() + "\n";
    else if (r.contains("predictability") && r["predictability"]["until_s"].is_number())
        md += "- the model run with the drive moved by half an encoder count either way parts at " +
              num(r["predictability"]["until_s"], "%.2f") +
              " s: the record cannot decide what follows, and the part before is too short to "
              "judge again (`predictability` in report.json)\n";
    if (r["fit_windows"]["windowed"].get<bool>())
        md += "- fitted on windows (`fit_windows` in report.json): " +
              r["fit_windows"]["rule"].get<std::string>() + "\n";
    md += "\n";
    md += "## Effects named\n\n";
    if (r["effects"].empty()) md += "None.\n";
    for (const Json& e : r["effects"]) {
        md += "### `" + e["name"].get<std::string>() + "` (explains " +
              num(e["share_explained"], "%.2f") + " of the held-out excess error)\n\nActs on " +
              e["where"]["acts"].get<std::string>() + ".\n\n";
        md += "| parameter | value | unit | SD | how |\n|---|---|---|---|---|\n";
        for (const Json& p : e["parameters"])
            md += "| " + p["name"].get<std::string>() + " | " +
                  (p["value"].is_number() ? num(p["value"], "%.5g") : p["value"].dump()) + " | " +
                  (p["unit"].is_string() ? p["unit"].get<std::string>() : "") + " | " +
                  num(p["sd"], "%.2g") + " | " +
                  (p["fitted"].get<bool>() ? "fitted" : p["how"].get<std::string>()) + " |\n";
        md += "\n";
    }
    md += equally_consistent_markdown(r);
    md +=
        "## Held-out RMS error per output\n\n| output | noise SD | before | after "
        "|\n|---|---|---|---|\n";
    for (const auto& [name, before] : r["rmse_before"].items())
        md += "| " + name + " | " + num(r["significance"]["outputs"][name]["noise_sd"], "%.3g") +
              " | " + num(before, "%.3g") + " | " + num(r["rmse_after"][name], "%.3g") + " |\n";
    md += "\n## Held-out RMS error per region (before → after)\n\n";
    for (const auto& [region, outputs] : r["rmse_by_region"].items()) {
        md += "- " + region + ":";
        for (const auto& [name, v] : outputs.items())
            md +=
                " " + name + " " + num(v["before"], "%.3g") + " → " + num(v["after"], "%.3g") + ";";
        md += "\n";
    }
    md +=
        "\n## Candidates (best held-out cost first)\n\n| effects | held-out cost | BIC | share "
        "explained |\n|---|---|---|---|\n";
    md += "| (model as given) | " + num(r["baseline"]["held_out_cost"], "%.4g") + " | " +
          num(r["baseline"]["bic"], "%.6g") + " | 0 |\n";
    for (const Json& c : r["candidates"]) {
        std::string names;
        for (const Json& n : c["effects"])
            names += (names.empty() ? "" : " + ") + n.get<std::string>();
        md += "| " + names + " | " +
              (c["ok"].get<bool>() ? num(c["held_out_cost"], "%.4g") : "failed") + " | " +
              num(c["bic"], "%.6g") + " | " + num(c["share_explained"], "%.2f") + " |\n";
    }
    md +=
        "\nCosts are sums over outputs of the mean squared held-out error in units of the noise "
        "(noise alone: " +
        num(r["baseline"]["noise_floor_cost"], "%.0f") + ").\n\n";
    md +=
        "## Plots\n\n![measured and model, before and after](outputs.png)\n\n![residual before and "
        "after](residuals.png)\n\n"
        "![the candidates' scores](candidates.png)\n" +
        (r.contains("screening") && r["screening"].is_object()
             ? std::string("\n![the screening profiles](profiles.png)\n")
             : std::string());
    return md;
}

int run_discrepancy_command(const DiscrepancyOptions& o) {
    if (o.thesis_cantilever != o.recording.empty()) {
        std::cerr
            << "scopekin discrepancy: give a recording or --thesis-cantilever (one of them)\n";
        return 2;
    }
    if (o.thesis_cantilever) return run_thesis_cantilever_case(o);
    recording::Recording rec;
    try {
        recording::RecordingReaderOptions reader_options;
        reader_options.max_gap_s = o.max_gap_s;
        rec = recording::RecordingReader(reader_options).read_file(o.recording);
    } catch (const recording::RecordingError& e) {
        std::cerr << "scopekin discrepancy: invalid recording: " << e.what() << "\n";
        return 2;
    }
    discrepancy::WorkflowOptions options;
    options.threads = o.threads;
    options.fit_budget_s = o.fit_budget_s;
    options.compare_only = o.compare_only;
    try {
        if (!o.model.empty()) {
            options.model = model::io::parse_json_file(o.model);
            options.model_source = o.model;
        } else {
            options.model = discrepancy::default_model();
        }
        const discrepancy::MeasuredRecording data =
            discrepancy::extract_measured_recording(rec, o.recording);
        const fs::path dir(o.out);
        prepare_directory(dir,
                          {"report.json", "report.md", "model.json", "series.csv", "outputs.png",
                           "residuals.png", "candidates.png", "profiles.png"});  // report first
        ProgressBar bar(o.quiet);
        options.progress = [&](const std::string& stage, double fraction) {
            bar.stage(fraction, stage);
        };
        const discrepancy::WorkflowResult result = discrepancy::run_discrepancy(data, options);
        bar.done();
        write_json(dir / "model.json", Json::parse(result.model.dump()));
        {
            PartFile md(dir / "report.md");
            md.stream() << report_markdown(result.report);
            md.finish(true);
        }
        {
            // The series behind the plots: every measured sample with the model before and after.
            PartFile series(dir / "series.csv");
            std::ostream& csv = series.stream();
            csv << "output,component,time_s,held_out,measured,before,after\n";
            const discrepancy::MeasuredRecording& judged = result.data;  // may be a part
            for (std::size_t k = 0; k < judged.outputs.size(); ++k) {
                const discrepancy::MeasuredSeries& m = judged.outputs[k];
                for (std::size_t i = 0; i < m.time_s.size(); ++i)
                    for (int c = 0; c < m.components; ++c)
                        csv << discrepancy::output_name(m.id) << ',' << "xyz"[c] << ','
                            << m.time_s[i] << ','
                            << (discrepancy::in_set(judged, m.time_s[i],
                                                    discrepancy::SampleSet::held_out)
                                    ? 1
                                    : 0)
                            << ',' << m.value[i][c] << ',' << result.before.outputs[k][i][c] << ','
                            << result.after.outputs[k][i][c] << '\n';
            }
            series.finish(true);
        }
        // report.json is renamed last of all, after the plots (drawn from report.json.part).
        const fs::path report_part = write_json_part(dir / "report.json", result.report);
        std::optional<ProgramResult> plots;
        if (o.plots) {
            // An argument vector, no shell: the folder's name reaches the script as it is.
            std::vector<std::string> argv{SCOPEKIN_PYTHON, SCOPEKIN_DISCREPANCY_PLOT_SCRIPT};
            if (o.quiet) argv.emplace_back("--quiet");
            argv.emplace_back("--report");
            argv.push_back(fs::absolute(report_part).string());
            argv.push_back(fs::absolute(dir).string());  // absolute: never taken for an option
            plots = run_program(argv);
        }
        commit_part(dir / "report.json");
        const Json& r = result.report;
        std::printf("verdict: %s\n", r["verdict"].get<std::string>().c_str());
        for (const Json& e : r["effects"]) {
            std::printf("  %s (explains %.2f of the held-out excess error):",
                        e["name"].get<std::string>().c_str(), e["share_explained"].get<double>());
            for (const Json& p : e["parameters"]) {
                if (!p["fitted"].get<bool>()) continue;
                if (!p["value"].is_number()) {
                    std::printf(" %s = %s;", p["name"].get<std::string>().c_str(),
                                p["value"].dump().c_str());
                    continue;
                }
                std::printf(" %s = %.4g", p["name"].get<std::string>().c_str(),
                            p["value"].get<double>());
                if (p["sd"].is_number()) std::printf(" ± %.2g", p["sd"].get<double>());
                std::printf(" %s;", p["unit"].get<std::string>().c_str());
            }
            std::printf("\n");
        }
        for (const Json& set : r["equally_consistent"]["sets"])
            std::printf("  explained as well by %s (the recording cannot tell them apart)\n",
                        fitted_set_text(set).c_str());
        std::printf("held-out RMS error (before -> after):\n");
        for (const auto& [name, before] : r["rmse_before"].items()) {
            const Json& noise = r["significance"]["outputs"][name]["noise_sd"];
            std::printf("  %-22s %10.4g -> %10.4g   (%s)\n", name.c_str(), before.get<double>(),
                        r["rmse_after"][name].get<double>(),
                        noise.is_number()
                            ? ("noise " + std::to_string(noise.get<double>()).substr(0, 6)).c_str()
                            : "noise unknown: not assessed");
        }
        if (plots && !plots->ok())
            throw OutputError(std::string("the plots could not be drawn (") +
                              SCOPEKIN_DISCREPANCY_PLOT_SCRIPT + " " + plots->describe() +
                              "); the report is complete without them");
        std::printf(
            "%zu model runs, %.1f s; wrote report.json, report.md, model.json, series.csv%s into "
            "%s\n",
            r["model_runs"].get<std::size_t>(), r["wall_time_s"].get<double>(),
            !o.plots ? ""
            : fs::exists(dir / "profiles.png")
                ? ", outputs.png, residuals.png, candidates.png, profiles.png"
                : ", outputs.png, residuals.png, candidates.png",
            dir.string().c_str());
        return 0;
    } catch (const discrepancy::DiscrepancyInputError& e) {
        std::cerr << "scopekin discrepancy: refused: " << e.what() << "\n";
        return 2;
    } catch (const model::ModelError& e) {
        std::cerr << "scopekin discrepancy: invalid model: " << e.what() << "\n";
        return 2;
    } catch (const OutputError& e) {
        std::cerr << "scopekin discrepancy: " << e.what() << "\n";
        return 3;
    }
}

}  // namespace

void add_discrepancy_command(CLI::App& app) {
    auto options = std::make_shared<DiscrepancyOptions>();
    CLI::App* cmd = app.add_subcommand(
        "discrepancy",
        "Find where a model and a recording disagree and name the missing physical effect "
        "(host_sim/discrepancy/"
        "README.md): drives the model with the recording's insertion and roll, compares the "
        "measured outputs (EM positions "
        "of the tip, the 20 cm point and the sigmoid, the tip force, the handle force and torque) "
        "against the noise "
        "estimated from the data, fits each candidate effect (then pairs) on training blocks and "
        "judges them on held-out "
        "blocks (a recording longer than the fit budget on one window per block, the named effects "
        "then over all of "
        "it). An unexplained recording whose model runs part when the drive moves by half an "
        "encoder count (a stick-or-slip branch) is judged again up to there. "
        "Writes DIR/report.json (verdict named/none/unexplained, or with --compare-only "
        "none/disagrees; effects with fitted "
        "parameters, units and SDs, "
        "RMS errors before and after), DIR/report.md with plots, DIR/model.json (the model with "
        "the named effects: a "
        "scenario can use it with \"model\": \"DIR/model.json\") and DIR/series.csv. With "
        "--thesis-cantilever, the "
        "thesis's measured cantilever as a static case instead (report.json, report.md). Exit "
        "status 0 done, 2 a recording "
        "or model it cannot use (the message says what is needed), 3 an output cannot be written.");
    cmd->add_option("recording", options->recording,
                    "Recording CSV file (host_sim/recording/RECORDING.md)")
        ->check(CLI::ExistingFile);
    cmd->add_flag("--thesis-cantilever", options->thesis_cantilever,
                  "Instead of a recording: the static real-data case, the thesis's measured "
                  "cantilever (Table 4.2): one EI "
                  "against EI along the scope (with and without the clamp's pitch), scored leaving "
                  "one point out");
    cmd->add_option("--model", options->model,
                    "The current model: a scenario file without procedure (colon, scope, solver, "
                    "truth_effects); default: "
                    "the default colon and the CF-Q160L, no effects")
        ->check(CLI::ExistingFile);
    cmd->add_option("--out", options->out,
                    "Output directory (created if missing; old outputs in it are replaced)")
        ->required();
    cmd->add_option("--threads", options->threads, "Model runs in parallel (1 .. 64)")
        ->default_val(2)
        ->check(whole_number())
        ->check(CLI::Range(1, 64));
    cmd->add_option("--max-gap-s", options->max_gap_s,
                    "Refuse a recording with two rows further apart than this [s] (the line is "
                    "named): the model would be run across the gap")
        ->default_val(recording::kDefaultMaxGap_s)
        ->check(positive_seconds());
    cmd->add_option("--fit-budget-s", options->fit_budget_s,
                    "Recording seconds one fit run simulates at most (at least 80: ten windows of "
                    "3 s spin-up and 5 s "
                    "scored; shorter windows were measured to mislead the fits). A longer "
                    "recording is fitted on one "
                    "window per block, restarted from the model-as-given run's state; the effects "
                    "finally named are "
                    "checked over the whole recording")
        ->default_val(discrepancy::kDefaultFitBudget_s)
        ->check(positive_seconds())
        ->check(CLI::Range(discrepancy::kMinFitBudget_s, 100000.0));
    cmd->add_flag("--compare-only", options->compare_only,
                  "Only drive the model and compare it with the recording (one model run): "
                  "verdict none when every output agrees within its noise, disagrees otherwise; "
                  "no effect is searched. E.g. a model.json checked against another recording, "
                  "or whether the true model of a simulated recording explains it")
        ->excludes("--thesis-cantilever");
    cmd->add_flag(
        "--no-plots", [options](std::int64_t) { options->plots = false; },
        "Write no PNG (the CSV and JSON only)");
    cmd->add_flag("--quiet", options->quiet, "No progress on stderr");
    cmd->callback([options]() { throw CLI::RuntimeError(run_discrepancy_command(*options)); });
}

}  // namespace scopekin::cli
