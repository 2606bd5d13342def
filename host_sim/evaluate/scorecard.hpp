#pragma once
// The scorecard (host_sim/evaluate/README.md, "Outputs"): every estimator of the registry
// scored on one case (score_case: the case's score.json), and the cases combined
// (aggregate: scorecard.json's "overall"), with the CSV (one row per case x estimator) and the
// Markdown table the README shows. Scores are JSON values, so that shards written on other
// machines merge without re-reading the run folders; a measure that cannot be computed is null
// ("n/a" in the tables).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/evaluate/case_run.hpp"
#include "host_sim/evaluate/estimators.hpp"

namespace scopekin::evaluate {

using Json = nlohmann::ordered_json;

/// The score of one case: its run's status and every estimator's measures (`outputs`: one per
/// registry entry, estimator_outputs(); empty for a run that is not complete).
/// `status`: "complete" (scored), "failed" (the run failed: listed, not scored), "not_run"
/// (no summary.json), "unscorable" (a file missing or malformed: `message` says which).
Json score_case(const std::string& name, const std::string& style, const std::string& folder,
                const CaseRun& run, const std::vector<EstimatorOutput>& outputs);
/// estimates.csv of a case: per period the truth (tip, largest station force, loop episode and
/// force level: 1 in a warning episode, 2 in a critical one) and every estimator's outputs
/// (<name>_tip_path_mm, _max_force_N, _loop_alarm, _contact_level; empty where not estimated).
std::string estimates_csv(const CaseRun& run, const std::vector<EstimatorOutput>& outputs);
/// A case that has no scorable run.
Json unscored_case(const std::string& name, const std::string& style, const std::string& folder,
                   const std::string& status, const std::string& message);

/// The cases combined: per estimator, each measure's median, 90th percentile and worst case
/// over the cases; detections, misses and false alarms pooled; the procedures' outcome (cecal
/// intubation per style, insertion at the cecum) where the runs report it.
Json aggregate(const std::vector<Json>& case_scores);

/// scorecard.csv: its header and one row per case x estimator.
std::string scorecard_csv_header();
std::vector<std::string> scorecard_csv_rows(const Json& case_score);

/// scorecard.md: the overall table (and the procedure outcome), titled with the manifest.
std::string scorecard_markdown(const Json& overall, const std::string& manifest_name,
                               const std::string& description);

}  // namespace scopekin::evaluate
