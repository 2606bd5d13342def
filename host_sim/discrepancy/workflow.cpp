#include "host_sim/discrepancy/workflow.hpp"

#include <chrono>
#include <optional>
#include <utility>

#include "host_sim/discrepancy/report.hpp"
#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {

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
    result.candidates = std::move(findings.candidates);
    return result;
}

}  // namespace scopekin::discrepancy
