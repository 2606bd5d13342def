#include "host_sim/discrepancy/report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>

#include "host_sim/discrepancy/ranking.hpp"
#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {

StageLog::StageLog(const Evaluator& evaluator,
                   std::function<void(const std::string&, double)> progress,
                   std::chrono::steady_clock::time_point started)
    : evaluator_(evaluator),
      progress_(std::move(progress)),
      started_(started),
      stage_started_(started) {}

void StageLog::start(const std::string& name, double fraction) {
    const auto now = std::chrono::steady_clock::now();
    if (!name_.empty())
        stages_.push_back(
            {{"stage", name_},
             {"model_runs", evaluator_.runs() - runs_},
             {"simulated_s", evaluator_.simulated_s() - simulated_s_},
             {"wall_time_s", std::chrono::duration<double>(now - stage_started_).count()}});
    name_ = name;
    runs_ = evaluator_.runs();
    simulated_s_ = evaluator_.simulated_s();
    stage_started_ = now;
    progress(name, fraction);
}

void StageLog::progress(const std::string& text, double fraction) const {
    if (progress_) progress_(text, fraction);
}

double StageLog::wall_time_s() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
}

namespace {

using Json = nlohmann::ordered_json;

Json rmse_per_output(const MeasuredRecording& data, const ModelPrediction& p, SampleSet set) {
    Json out = Json::object();
    for (std::size_t o = 0; o < data.outputs.size(); ++o)
        out[output_name(data.outputs[o].id)] = rms_error(data, p, o, set);
    return out;
}

/// Held-out RMS error per region (the recording's label, else the model's) and output.
Json rmse_by_region(const MeasuredRecording& data, const ModelPrediction& before,
                    const ModelPrediction& after) {
    std::map<std::string, std::vector<std::array<double, 3>>>
        acc;  // region -> per output (sum before, sum after, n)
    for (std::size_t o = 0; o < data.outputs.size(); ++o) {
        const MeasuredSeries& m = data.outputs[o];
        for (std::size_t i = 0; i < m.time_s.size(); ++i) {
            if (!in_set(data, m.time_s[i], SampleSet::held_out)) continue;
            std::string region = data.region_at(m.time_s[i]);
            if (region.empty()) region = before.region_at(m.time_s[i]);
            if (region.empty()) region = "outside";
            auto& slot = acc[region];
            slot.resize(data.outputs.size(), {0.0, 0.0, 0.0});
            slot[o][0] += (m.value[i] - before.outputs[o][i]).squaredNorm();
            slot[o][1] += (m.value[i] - after.outputs[o][i]).squaredNorm();
            slot[o][2] += 1.0;
        }
    }
    Json out = Json::object();
    for (const auto& [region, per_output] : acc) {
        Json r = Json::object();
        for (std::size_t o = 0; o < data.outputs.size(); ++o) {
            if (per_output[o][2] == 0.0) continue;
            r[output_name(data.outputs[o].id)] = {
                {"samples", static_cast<std::size_t>(per_output[o][2])},
                {"before", std::sqrt(per_output[o][0] / per_output[o][2])},
                {"after", std::sqrt(per_output[o][1] / per_output[o][2])}};
        }
        out[region] = r;
    }
    return out;
}

/// The parameters of each effect of a fit: fitted ones with unit and SD, held ones marked.
Json effect_parameters(const EffectSetFit& fit, std::size_t k) {
    const Candidate& c = candidate_library()[fit.candidates[k]];
    std::size_t at = 0;
    for (std::size_t j = 0; j < k; ++j)
        at += candidate_library()[fit.candidates[j]].parameters.size();
    Json params = Json::array();
    // A null SD says why (the fit's reason for that parameter, or for the pair it comes from).
    auto why = [&](std::size_t i) {
        return fit.sd_unavailable.size() > i && !fit.sd_unavailable[i].empty()
                   ? fit.sd_unavailable[i]
                   : std::string("not computed (no uncertainty pass for this fit)");
    };
    auto with_sd = [&](Json param, double sd, std::size_t i) {
        param["sd"] = std::isfinite(sd) ? Json(sd) : Json(nullptr);
        if (!std::isfinite(sd)) param["sd_unavailable"] = why(i);
        return param;
    };
    if (c.name == "sigmoid_mobility") {
        // Fitted as A cos(phi), A sin(phi); reported as A and phi (first-order error propagation).
        const double a = fit.values[at], b = fit.values[at + 1];
        const double sa = fit.sd.size() > at ? fit.sd[at] : NAN,
                     sb = fit.sd.size() > at + 1 ? fit.sd[at + 1] : NAN;
        const double amp = std::hypot(a, b);
        const double sd_amp = amp > 0 ? std::hypot(a * sa, b * sb) / amp : NAN;
        const double sd_phase = amp > 0 ? std::hypot(b * sa, a * sb) / (amp * amp) : NAN;
        const std::size_t ab = std::isfinite(sa) ? at + 1 : at;  // the reason of the pair
        Json amplitude = with_sd(
            {{"name", "amplitude_N_per_mm"}, {"value", amp}, {"unit", "N/mm"}, {"fitted", true}},
            sd_amp, ab);
        Json phase = with_sd(
            {{"name", "phase_rad"}, {"value", std::atan2(b, a)}, {"unit", "rad"}, {"fitted", true}},
            sd_phase, ab);
        if (!(amp > 0)) {  // propagated through the amplitude: undefined at 0
            amplitude["sd_unavailable"] = "the fitted amplitude is 0 (the effect is absent)";
            phase["sd_unavailable"] = "the fitted amplitude is 0: the phase is undefined";
        }
        params.push_back(amplitude);
        params.push_back(phase);
        params.push_back(
            {{"name", "frequency_Hz"},
             {"value", fit.held[k]["frequency_Hz"]},
             {"unit", "Hz"},
             {"sd", nullptr},
             {"fitted", false},
             {"how",
              "screened, not fitted: the residual's periodogram (0.05-2 Hz, 0.01 Hz grid: the "
              "strongest power, or on a recording of 100 s or more the most prominent line); on a "
              "recording fitted on full runs, the frequency of the lowest training cost among it "
              "and the dips of the model's response scan (report.json screening, "
              "sigmoid_mobility, frequency)"}});
        const double polar = fit.values[at + 2], azimuth = fit.values[at + 3];
        params.push_back({{"name", "direction"},
                          {"value",
                           {std::sin(polar) * std::cos(azimuth),
                            std::sin(polar) * std::sin(azimuth), std::cos(polar)}},
                          {"unit", "1"},
                          {"sd", nullptr},
                          {"sd_unavailable",
                           "a unit vector: the SDs are those of direction_polar_rad and "
                           "direction_azimuth_rad"},
                          {"fitted", true},
                          {"how", "fitted as direction_polar_rad, direction_azimuth_rad"}});
        for (std::size_t j = 2; j < 4; ++j) {
            const double sd = fit.sd.size() > at + j ? fit.sd[at + j] : NAN;
            params.push_back(with_sd({{"name", c.parameters[j].key},
                                      {"value", fit.values[at + j]},
                                      {"unit", "rad"},
                                      {"fitted", true}},
                                     sd, at + j));
        }
        return params;
    }
    for (std::size_t j = 0; j < c.parameters.size(); ++j) {
        const double sd = fit.sd.size() > at + j ? fit.sd[at + j] : NAN;
        params.push_back(with_sd({{"name", c.parameters[j].key},
                                  {"value", fit.values[at + j]},
                                  {"unit", c.parameters[j].unit},
                                  {"fitted", true}},
                                 sd, at + j));
    }
    for (const auto& [key, value] : fit.held[k].items())
        params.push_back({{"name", key},
                          {"value", value},
                          {"unit", nullptr},
                          {"sd", nullptr},
                          {"fitted", false},
                          {"how", "held"}});
    return params;
}

/// The named effects (report.json "effects"): parameters, where each acts and closes the gap,
/// and its share of the held-out excess error.
Json effects_json(const DiscrepancyContext& context, const Findings& findings,
                  const Json& by_region) {
    Json effects = Json::array();
    if (!findings.verdict.named) return effects;
    const MeasuredRecording& data = context.data;
    const EffectSetFit& named = findings.candidates[*findings.verdict.named];
    const std::size_t most_affected = findings.significance.most_affected;
    const double cost_before = context.cost_before, floor = context.noise_floor;
    const double cost_after = named.held_out_cost;
    for (std::size_t k = 0; k < named.candidates.size(); ++k) {
        const Candidate& c = candidate_library()[named.candidates[k]];
        double share = share_explained(cost_before, cost_after, floor);
        if (named.candidates.size() > 1) {
            // Its own share: what the pair explains beyond the other effect alone.
            for (const EffectSetFit& f : findings.candidates)
                if (f.candidates.size() == 1 && f.candidates[0] != named.candidates[k])
                    if (std::find(named.candidates.begin(), named.candidates.end(),
                                  f.candidates[0]) != named.candidates.end())
                        share = share_explained(cost_before, cost_after, floor) -
                                share_explained(context.cost_before_fit, f.held_out_cost, floor);
        }
        Json regions = Json::array();
        for (const auto& [region, outputs] : by_region.items()) {
            const Json& m = outputs.contains(output_name(data.outputs[most_affected].id))
                                ? outputs[output_name(data.outputs[most_affected].id)]
                                : Json();
            if (!m.is_null() &&
                m["before"].get<double>() >
                    context.options.significance * context.sigma[most_affected] &&
                m["after"].get<double>() < 0.5 * m["before"].get<double>())
                regions.push_back(region);
        }
        effects.push_back(
            {{"name", c.name},
             {"parameters", effect_parameters(named, k)},
             {"where", {{"acts", c.acts}, {"regions_where_it_closes_the_gap", regions}}},
             {"share_explained", share},
             {"entry", named.effects[k]}});
    }
    return effects;
}

/// Every fit with its scores (report.json "candidates"); the named set's share on the full runs.
Json candidates_json(const DiscrepancyContext& context, const Findings& findings) {
    Json candidates = Json::array();
    for (std::size_t i = 0; i < findings.candidates.size(); ++i) {
        const EffectSetFit& f = findings.candidates[i];
        const bool named = findings.verdict.named && *findings.verdict.named == i;
        Json params = Json::array();
        if (f.ok)
            for (std::size_t k = 0; k < f.candidates.size(); ++k)
                params.push_back(effect_parameters(f, k));
        candidates.push_back(
            {{"effects", names_of(f)},
             {"ok", f.ok},
             {"failure", f.ok ? Json(nullptr) : Json(f.failure)},
             {"parameters", params},
             {"training_cost", f.training_cost},
             {"held_out_cost", f.held_out_cost},
             {"bic", f.bic},
             {"share_explained",
              f.ok ? share_explained(named ? context.cost_before : context.cost_before_fit,
                                     f.held_out_cost, context.noise_floor)
                   : 0.0},
             {"iterations", f.iterations}});
        if (!f.valley_walk.is_null()) candidates.back()["valley_walk"] = f.valley_walk;
    }
    return candidates;
}

/// The candidates the recording cannot tell from the named set (report.json "equally_consistent").
Json equally_consistent_json(const Findings& findings) {
    Json sets = Json::array();
    for (std::size_t i : findings.verdict.equally_consistent) {
        const EffectSetFit& f = findings.candidates[i];
        Json params = Json::array();
        for (std::size_t k = 0; k < f.candidates.size(); ++k)
            params.push_back(effect_parameters(f, k));
        sets.push_back(
            {{"effects", names_of(f)}, {"parameters", params}, {"held_out_cost", f.held_out_cost}});
    }
    char margin[32];
    std::snprintf(margin, sizeof margin, "%g", kMinRestCost);
    return {
        {"rule", std::string("the other candidates whose held-out cost is at most ") + margin +
                     " above the named set's, or which like it leave less than " + margin +
                     " above the noise floor: this recording cannot tell them from the named set "
                     "(costs on the fit windows when fitted on windows)"},
        {"sets", sets}};
}

/// The fit windows and the confirmation on the whole recording (report.json "fit_windows").
Json fit_windows_json(const DiscrepancyContext& context, const Findings& findings) {
    const std::vector<RunWindow>& windows = context.windows;
    Json window_list = Json::array();
    for (const RunWindow& w : windows)
        window_list.push_back({{"block", w.block},
                               {"start_s", w.start_s},
                               {"scored_from_s", w.score_from_s},
                               {"end_s", w.end_s}});
    return {
        {"budget_s", context.options.fit_budget_s},
        {"windowed", !windows.empty()},
        {"rule",
         windows.empty()
             ? "the blocks fit the budget: every run covers the whole recording"
             : "one window per block where the hand moves most, restarted from the baseline's "
               "state; "
               "the first " +
                   std::to_string(windows.front().score_from_s - windows.front().start_s) +
                   " s of each is spin-up, not scored; the candidates' costs are on these windows, "
                   "before/after figures on full runs"},
        {"windows", window_list},
        {"confirmation", findings.verdict.confirmation}};
}

}  // namespace

Json build_report(const DiscrepancyContext& context, const Findings& findings,
                  const StageLog& stages) {
    const MeasuredRecording& data = context.data;
    const ModelPrediction& before = context.baseline;
    const ModelPrediction& after = findings.verdict.named
                                       ? findings.candidates[*findings.verdict.named].prediction
                                       : context.baseline;
    const std::size_t most_affected = findings.significance.most_affected;
    const Json by_region = rmse_by_region(data, before, after);
    Json r;
    r["recording"] = data.source;
    r["model"] = context.options.model_source;
    r["verdict"] = findings.verdict.verdict;
    r["compare_only"] = context.options.compare_only;
    r["effects"] = effects_json(context, findings, by_region);
    r["equally_consistent"] = equally_consistent_json(findings);
    r["rmse_before"] = rmse_per_output(data, before, SampleSet::held_out);
    r["rmse_after"] = rmse_per_output(data, after, SampleSet::held_out);
    const double before_most = rms_error(data, before, most_affected, SampleSet::held_out);
    const double after_most = rms_error(data, after, most_affected, SampleSet::held_out);
    r["most_affected_output"] = {
        {"name", output_name(data.outputs[most_affected].id)},
        {"held_out_rmse_before", before_most},
        {"held_out_rmse_after", after_most},
        {"reduction", before_most > 0 ? 1.0 - after_most / before_most : 0.0}};
    r["rmse_by_region"] = by_region;
    r["significance"] = {{"threshold_rms_over_noise", context.options.significance},
                         {"outputs", findings.significance.outputs}};
    r["held_out"] = {{"blocks", kBlocks},
                     {"held_out_blocks", {1, 4, 7}},
                     {"rule",
                      "the drive's span in 10 equal blocks; blocks 1, 4, 7 held out (residuals are "
                      "autocorrelated)"}};
    r["candidates"] = candidates_json(context, findings);
    r["screening"] = findings.screening;
    r["pair_test"] = findings.pair_test;
    r["baseline"] = {{"held_out_cost", context.cost_before},
                     {"noise_floor_cost", context.noise_floor},
                     {"training_noise_floor_cost", context.training_noise_floor()},
                     {"bic", bic_of(context, before, 0)}};
    r["location"] = locate(data, before, context.sigma, context.options.significance);
    r["recording_span_s"] = {data.start_s, data.end_s};
    r["fit_windows"] = fit_windows_json(context, findings);
    r["model_runs"] = context.evaluator.runs();
    r["repeated_requests"] = context.evaluator.repeats();  // answered with a stored run
    r["simulated_s"] = context.evaluator.simulated_s();
    r["stages"] = stages.stages();
    r["wall_time_s"] = stages.wall_time_s();
    return r;
}

}  // namespace scopekin::discrepancy
