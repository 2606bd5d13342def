#pragma once
// What the discrepancy workflow reports: report.json (host_sim/discrepancy/README.md, step 6),
// built from the context and what the stages found, and the stages' own log: runs, recording
// seconds simulated and wall time per stage (report.json "stages"), with the progress shown
// while they run.
#include <chrono>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/context.hpp"
#include "host_sim/discrepancy/evaluator.hpp"

namespace scopekin::discrepancy {

struct Findings;

class StageLog {
public:
    /// `started`: when the workflow started (report.json "wall_time_s" counts from there).
    StageLog(const Evaluator& evaluator, std::function<void(const std::string&, double)> progress,
             std::chrono::steady_clock::time_point started);
    /// Ends the stage running, if any, and starts `name` with `fraction` of the whole done.
    void start(const std::string& name, double fraction);
    /// Progress within a stage.
    void progress(const std::string& text, double fraction) const;
    /// The stages ended so far.
    const nlohmann::ordered_json& stages() const { return stages_; }
    double wall_time_s() const;

private:
    const Evaluator& evaluator_;
    std::function<void(const std::string&, double)> progress_;
    std::chrono::steady_clock::time_point started_;
    nlohmann::ordered_json stages_ = nlohmann::ordered_json::array();
    std::string name_;
    std::size_t runs_ = 0;
    double simulated_s_ = 0.0;
    std::chrono::steady_clock::time_point stage_started_;
};

/// report.json.
nlohmann::ordered_json build_report(const DiscrepancyContext& context, const Findings& findings,
                                    const StageLog& stages);

}  // namespace scopekin::discrepancy
