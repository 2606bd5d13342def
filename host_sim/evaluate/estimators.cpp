#include "host_sim/evaluate/estimators.hpp"

#include <cmath>

#include "host_sim/simulator/box_observer.hpp"

namespace scopekin::evaluate {
namespace {

/// (a) The box as it is: firmware.csv's published outputs — its tip (the reduced model's while
/// the handle's evidence trusts it, else the slack regressor's) and its uncertainty; the largest
/// contact force (likewise the model's or the contact force trees'); the loop alarm (likewise the
/// model's self-lock or the loop alarm from evidence); the contact-force level on that published
/// force (the reduced model's in runs written before 2026-11-30); the faults.
EstimatorOutput box(const CaseRun& run, const EstimatorContext&) {
    EstimatorOutput o;
    o.tip_path_mm = run.box_tip_path_mm;
    o.tip_uncertainty_mm = run.box_tip_uncertainty_mm;
    o.max_force_N = run.box_max_contact_force_N;
    o.loop_alarm = run.box_self_lock;
    o.contact_level = run.box_contact_level;
    o.fault_flags = run.box_fault_flags;
    return o;
}

/// (b) The depth replay: the reduced model's own tip, largest force, self-lock alarm and
/// contact-force level (firmware.csv model_tip_path_mm, model_max_contact_force_N,
/// model_self_lock_alarm, model_contact_force_level: the box's published ones until the tip
/// observer, the contact force trees, the loop alarm from evidence and the level from evidence);
/// the box's faults.
EstimatorOutput depth_replay(const CaseRun& run, const EstimatorContext& context) {
    EstimatorOutput o = box(run, context);
    o.tip_path_mm = run.box_model_tip_path_mm;
    o.max_force_N = run.box_model_max_contact_force_N;
    o.loop_alarm = run.box_model_self_lock;
    o.contact_level = run.box_model_contact_level;
    o.tip_uncertainty_mm.clear();
    return o;
}

/// (c) The handle force monitor (force_monitor.hpp): alarms only.
EstimatorOutput handle_force_monitor(const CaseRun& run, const EstimatorContext& context) {
    const ForceMonitorFeatures f = force_monitor_features(run);
    const ForceMonitorThresholds& t = context.force_monitor;
    EstimatorOutput o;
    o.loop_alarm = force_monitor_loop_alarm(f, t.loop_force_N, t.loop_rate_N_per_s);
    o.contact_level = force_monitor_contact_level(f, t);
    return o;
}

/// (d) Insertion depth as the tip: the tip put at the measured insertion along the colon, as if
/// the scope ran straight down the centerline with no slack; no force estimate, no alarms. The
/// simplest tip estimate that covers the whole procedure in every patient: what any estimator
/// must beat on tip position before its model earns anything (issue 21).
EstimatorOutput insertion_depth(const CaseRun& run, const EstimatorContext&) {
    EstimatorOutput o;
    o.tip_path_mm = run.handle_insertion_mm;
    for (double& mm : o.tip_path_mm)  // before the first sample: at the anus
        if (std::isnan(mm)) mm = 0.0;
    o.loop_alarm.assign(run.time_s.size(), 0);
    o.contact_level.assign(run.time_s.size(), 0);
    return o;
}

/// Alarm up over each episode, from its confirmation (else its onset) to its end (else the run's).
std::vector<std::uint8_t> confirmed_episodes(const std::vector<double>& time_s,
                                             const std::vector<Episode>& episodes) {
    std::vector<std::uint8_t> up(time_s.size(), 0);
    for (const Episode& e : episodes) {
        const double from = e.confirmed_s.value_or(e.onset_s);
        for (std::size_t k = 0; k < time_s.size(); ++k)
            if (time_s[k] >= from && (!e.end_s || time_s[k] < *e.end_s)) up[k] = 1;
    }
    return up;
}

/// (e) The definitions' own confirmation (a reference, not an estimator): a detector that knew
/// the true tip and forces exactly and raised each alarm when the truth's definition confirms
/// the episode (model/truth/README.md): a loop when the excess reaches 20 mm, which the truth then
/// dates back to the knee where the take-up began; a contact level when the force crosses it.
/// What it scores within 0.5 s of the onset is what waiting for the definition's own evidence
/// can score; an alarm that beats it must raise before the definition says "loop".
EstimatorOutput definitions_confirmation(const CaseRun& run, const EstimatorContext&) {
    EstimatorOutput o;
    o.loop_alarm = confirmed_episodes(run.time_s, run.loop_episodes);
    const std::vector<std::uint8_t> warning = confirmed_episodes(run.time_s, run.warning_episodes);
    const std::vector<std::uint8_t> critical =
        confirmed_episodes(run.time_s, run.critical_episodes);
    o.contact_level.resize(run.time_s.size());
    for (std::size_t k = 0; k < run.time_s.size(); ++k)
        o.contact_level[k] = critical[k] != 0 ? 2 : (warning[k] != 0 ? 1 : 0);
    return o;
}

}  // namespace

const std::vector<Estimator>& estimator_registry() {
    static const std::vector<Estimator> registry{
        {"box",
         "the box (slack regressor, contact force trees and loop alarm from evidence; the model's "
         "where the handle agrees with it; contact-force level on its published force; with the "
         "bench's EM tracker: the tip odometer and the loop alarm's slack gate)",
         box},
        {"depth_replay", "depth replay (the reduced model's tip, force and alarms)", depth_replay},
        {"force_monitor", "handle force monitor (baseline)", handle_force_monitor},
        {"insertion_depth", "insertion depth as the tip (baseline, no alarms)", insertion_depth},
        {"definitions_confirmation",
         "the truth's definitions, confirmed (reference, not an estimator: each alarm raised when "
         "the definition confirms the episode, a loop at 20 mm of excess)",
         definitions_confirmation},
    };
    return registry;
}

std::vector<EstimatorOutput> estimator_outputs(const CaseRun& run,
                                               const EstimatorContext& context) {
    std::vector<EstimatorOutput> outputs;
    for (const Estimator& e : estimator_registry())
        outputs.push_back(e.outputs(run, context));
    return outputs;
}

const std::vector<std::string>& fault_flag_names() {
    static const std::vector<std::string> names = [] {
        std::vector<std::string> n;
        for (const char* name : host_sim::kinetics_fault_names())
            n.emplace_back(name);
        return n;
    }();
    return names;
}

}  // namespace scopekin::evaluate
