#pragma once
// The discrepancy workflow (host_sim/discrepancy/README.md): simulate the recording's hand motion
// with the model, locate where model and measurement disagree beyond the sensor noise, fit the
// candidate effects (screening all, refining the best; then pairs) on the training blocks, judge
// them on the held-out blocks, and give a verdict:
//   none        no output's held-out RMS error exceeds `significance` times its noise;
//   named       the best single effect explains at least `min_share` of the held-out excess
//               error. If it leaves an output significant and a second effect is predicted to
//               remove a quarter of what is left (best_partner_gain), or if it explains less
//               than min_share but at least 10 %, the two pairs best by their linearised joint
//               step are fitted (side by side), and the best is named instead when it explains
//               min_share, beats the single's BIC and explains 5 % more;
//   unexplained otherwise (no single effect or pair explains min_share): the candidates are
//               reported, none is named. Fitted on full runs, an unexplained recording is then
//               tested for how far its encoder decides the best candidate's prediction
//               (predictability.hpp); where a stick-or-slip branch that the encoder cannot
//               resolve ends that with at least kMinDuration_s before it, the workflow runs again
//               on that part alone and returns its result (report.json "predictability").
// "Excess error" is the held-out normalised cost minus what the noise alone gives (1 per output).
// A recording longer than the fit budget is fitted on windows (fit_windows.hpp): the candidates'
// costs are then on the windows, and the named effects are run over the whole recording, where
// they must explain min_share again (else the verdict is unexplained).
// The steps are functions of their own (stages.hpp), called in order by run_discrepancy; they
// share one context (context.hpp), and report.hpp builds report.json.
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/context.hpp"
#include "host_sim/discrepancy/fit.hpp"
#include "host_sim/discrepancy/measured_recording.hpp"

namespace scopekin::discrepancy {

struct WorkflowResult {
    MeasuredRecording data;         ///< the recording judged (its predictable part, or all of it)
    nlohmann::ordered_json report;  ///< report.json
    nlohmann::json model;           ///< model.json: the input model with the named effects added
    ModelPrediction before;         ///< the model as given
    ModelPrediction after;          ///< with the named effects (= before unless named)
    std::vector<EffectSetFit> candidates;  ///< every fit, best first (held-out cost)
};

/// Throws model::ModelError for a model that cannot be built; a model that cannot follow the
/// recording (the run fails) throws DiscrepancyInputError saying where.
WorkflowResult run_discrepancy(const MeasuredRecording& recording, const WorkflowOptions& options);

}  // namespace scopekin::discrepancy
