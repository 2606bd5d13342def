#include "host_sim/discrepancy/workflow.hpp"

#include <chrono>
#include <functional>
#include <optional>
#include <utility>

#include "host_sim/discrepancy/predictability.hpp"
#include "host_sim/discrepancy/report.hpp"
#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {
namespace {

/// An unexplained recording fitted on full runs: does its encoder decide the best candidate's
/// prediction to the end (predictability.hpp)? If it stops doing so with at least kMinDuration_s
/// before that, the recording is judged again up to there (a second pass, which does not test
/// again) and that pass's result returned, its report saying why and what the first pass found.
std::optional<WorkflowResult> judge_predictable_part(const DiscrepancyContext& context,
                                                     const Findings& findings,
                                                     nlohmann::ordered_json& first_report,
                                                     StageLog& stages) {
    stages.start("how far the encoder decides the prediction", 1.0);
    // The best held-out cost's fit; the model as given if no fit ran.
    const EffectSetFit* best = nullptr;
    for (const EffectSetFit& f : findings.candidates)
        if (f.ok) {
            best = &f;
            break;
        }
    Predictability test =
        best != nullptr ? assess_predictability(context, best->effects, best->prediction)
                        : assess_predictability(context, nlohmann::json::array(), context.baseline);
    const MeasuredRecording& data = context.data;
    nlohmann::ordered_json note = test.report;
    note["first_pass"] = {{"verdict", first_report["verdict"]},
                          {"recording_span_s", first_report["recording_span_s"]},
                          {"candidates", first_report["candidates"]},
                          {"most_affected_output", first_report["most_affected_output"]},
                          {"model_runs", first_report["model_runs"]},
                          {"wall_time_s", first_report["wall_time_s"]}};
    note["predictability_runs"] = kPredictabilityRuns;
    if (!test.until_s || *test.until_s - data.start_s < kMinDuration_s) {
        note["judged_again"] = false;
        note["why"] = !test.until_s
                          ? "the runs never part: the record decides the prediction"
                          : "less than " + std::to_string(static_cast<int>(kMinDuration_s)) +
                                " s would be left to judge";
        first_report["predictability"] = note;
        first_report["model_runs"] =
            first_report["model_runs"].get<std::size_t>() + kPredictabilityRuns;
        first_report["wall_time_s"] = stages.wall_time_s();
        return std::nullopt;
    }
    WorkflowOptions again = context.options;
    again.judge_predictable_part = false;
    const std::function<void(const std::string&, double)> progress = context.options.progress;
    if (progress)
        again.progress = [progress](const std::string& stage, double f) {
            progress("the predictable part: " + stage, f);
        };
    WorkflowResult part = run_discrepancy(truncated_at(data, *test.until_s), again);
    note["judged_again"] = true;
    note["why"] =
        "the record stops deciding the prediction: the recording judged again up to "
        "there";
    nlohmann::ordered_json& r = part.report;
    r["predictability"] = note;
    r["model_runs"] = r["model_runs"].get<std::size_t>() +
                      first_report["model_runs"].get<std::size_t>() + kPredictabilityRuns;
    r["repeated_requests"] = r["repeated_requests"].get<std::size_t>() +
                             first_report["repeated_requests"].get<std::size_t>();
    r["wall_time_s"] = stages.wall_time_s();
    return part;
}

}  // namespace

WorkflowResult run_discrepancy(const MeasuredRecording& recording, const WorkflowOptions& options) {
    const auto started = std::chrono::steady_clock::now();
    // The recording with its fit windows, the noise estimated from it, the model: once, for all.
    DiscrepancyContext context(recording, options);
    StageLog stages(context.evaluator, options.progress, started);

    // 1. Drive and compare: the model as given, driven by the recording's encoder.
    stages.start("the model as given", 0.0);
    context.run_model_as_given(
        [&](double f) { stages.progress("the model as given", f / kProgressSteps); });

    // 2. Noise and significance: if no output disagrees beyond its noise, the verdict is none.
    Findings findings;
    findings.significance = assess_significance(context);

    // 3. Held-out blocks (and fit windows) are the context's: every score below is on them.
    // 4. Naming: screening, refinement, pairs, verdict.
    if (findings.significance.any && options.compare_only) {
        findings.verdict.verdict = "disagrees";
    } else if (findings.significance.any) {
        stages.start("screening the candidates", 1.0 / kProgressSteps);
        Screening screening = screen_candidates(context);
        const std::vector<EffectSetFit>& screened = screening.fits;
        findings.screening = std::move(screening.report);
        findings.candidates = refine_candidates(context, screened, stages);
        PairsOutcome pairs = try_pairs(context, screened, findings.candidates, stages);
        findings.pair_test = std::move(pairs.pair_test);
        findings.verdict = give_verdict(context, pairs.chosen, findings.candidates, stages);
    }
    stages.start("report", 1.0);

    // 5. Add: model.json is the model with the named effects appended to its truth_effects.
    // 6. Show: report.json, and the predictions before and after for the series and plots.
    WorkflowResult result;
    const std::optional<std::size_t> named = findings.verdict.named;
    result.model = named ? with_effects(context.model, findings.candidates[*named].effects)
                         : context.model.document;
    result.before = context.baseline;
    result.after = named ? findings.candidates[*named].prediction : context.baseline;
    result.report = build_report(context, findings, stages);
    // 7. An unexplained recording whose encoder stops deciding the prediction: its predictable
    // part judged again (full runs only: a windowed recording's runs restart every window).
    if (findings.verdict.verdict == "unexplained" && options.judge_predictable_part &&
        !context.evaluator.windowed()) {
        std::optional<WorkflowResult> part =
            judge_predictable_part(context, findings, result.report, stages);
        if (part) return std::move(*part);
    }
    result.data = context.data;
    result.candidates = std::move(findings.candidates);
    return result;
}

}  // namespace scopekin::discrepancy
