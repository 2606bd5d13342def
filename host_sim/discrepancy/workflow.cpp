#include "host_sim/discrepancy/workflow.hpp"

#include <algorithm>
#include <chrono>
#include <future>
#include <cmath>
#include <map>
#include <optional>

#include "host_sim/discrepancy/analysis.hpp"

namespace scopekin::discrepancy {
namespace {

using Json = nlohmann::ordered_json;

/// Candidates refined after screening (the rest keep their one-step fit).
constexpr std::size_t kRefined = 2;
/// Pairs refined after the linearised ranking.
constexpr std::size_t kPairs = 2;
/// How much more of the excess error a pair must explain than the best single effect.
constexpr double kPairGain = 0.05;
/// Pairs are tried only when the best single effect explains at least this much: when no effect
/// of the library explains anything alone, the disagreement is not theirs (and the pairs' runs
/// are saved).
constexpr double kMinSingleShareForPairs = 0.1;
/// When the best single effect explains min_share but leaves an output significant, pairs are
/// tried only if a second effect is predicted (linearly, best_partner_gain) to remove at least
/// this share of the single's remaining excess training cost: what is left may be the single's
/// own misfit, which no partner removes.
constexpr double kMinPartnerGain = 0.25;
/// Shares of the held-out excess error closer than this count as equal (the BIC decides).
constexpr double kTieShare = 0.02;
/// A runner-up whose screening step comes this close to the refined best is refined too.
constexpr double kRefineNear = 0.1;

/// Share of the held-out excess error (cost above the noise floor) a fit removes, in [0, 1].
double share_explained(double cost_before, double cost_after, double floor) {
  const double excess = cost_before - floor;
  if (!(excess > 0.0)) return 0.0;
  return std::clamp((cost_before - cost_after) / excess, 0.0, 1.0);
}

Json rmse_per_output(const BenchData& data, const ModelPrediction& p, SampleSet set) {
  Json out = Json::object();
  for (std::size_t o = 0; o < data.outputs.size(); ++o) out[output_name(data.outputs[o].id)] = rms_error(data, p, o, set);
  return out;
}

/// Held-out RMS error per region (the recording's label, else the model's) and output.
Json rmse_by_region(const BenchData& data, const ModelPrediction& before, const ModelPrediction& after) {
  std::map<std::string, std::vector<std::array<double, 3>>> acc;  // region -> per output (sum before, sum after, n)
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
      r[output_name(data.outputs[o].id)] = {{"samples", static_cast<std::size_t>(per_output[o][2])},
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
  for (std::size_t j = 0; j < k; ++j) at += candidate_library()[fit.candidates[j]].parameters.size();
  Json params = Json::array();
  if (c.name == "sigmoid_mobility") {
    // Fitted as A cos(phi), A sin(phi); reported as A and phi (first-order error propagation).
    const double a = fit.values[at], b = fit.values[at + 1];
    const double sa = fit.sd.size() > at ? fit.sd[at] : NAN, sb = fit.sd.size() > at + 1 ? fit.sd[at + 1] : NAN;
    const double amp = std::hypot(a, b);
    const double sd_amp = amp > 0 ? std::hypot(a * sa, b * sb) / amp : NAN;
    const double sd_phase = amp > 0 ? std::hypot(b * sa, a * sb) / (amp * amp) : NAN;
    params.push_back({{"name", "amplitude_N_per_mm"}, {"value", amp}, {"unit", "N/mm"}, {"sd", sd_amp}, {"fitted", true}});
    params.push_back({{"name", "phase_rad"}, {"value", std::atan2(b, a)}, {"unit", "rad"}, {"sd", sd_phase}, {"fitted", true}});
    params.push_back({{"name", "frequency_Hz"}, {"value", fit.held[k]["frequency_Hz"]}, {"unit", "Hz"}, {"sd", nullptr},
                      {"fitted", false}, {"how", "read off the residual (its strongest periodic component, 0.01 Hz grid)"}});
    const double polar = fit.values[at + 2], azimuth = fit.values[at + 3];
    params.push_back({{"name", "direction"},
                      {"value", {std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth), std::cos(polar)}},
                      {"unit", "1"}, {"sd", nullptr}, {"fitted", true},
                      {"how", "fitted as direction_polar_rad, direction_azimuth_rad"}});
    for (std::size_t j = 2; j < 4; ++j) {
      const double sd = fit.sd.size() > at + j ? fit.sd[at + j] : NAN;
      params.push_back({{"name", c.parameters[j].key}, {"value", fit.values[at + j]}, {"unit", "rad"},
                        {"sd", std::isfinite(sd) ? Json(sd) : Json(nullptr)}, {"fitted", true}});
    }
    return params;
  }
  for (std::size_t j = 0; j < c.parameters.size(); ++j) {
    const double sd = fit.sd.size() > at + j ? fit.sd[at + j] : NAN;
    params.push_back({{"name", c.parameters[j].key},
                      {"value", fit.values[at + j]},
                      {"unit", c.parameters[j].unit},
                      {"sd", std::isfinite(sd) ? Json(sd) : Json(nullptr)},
                      {"fitted", true}});
  }
  for (const auto& [key, value] : fit.held[k].items())
    params.push_back({{"name", key}, {"value", value}, {"unit", nullptr}, {"sd", nullptr}, {"fitted", false}, {"how", "held"}});
  return params;
}

std::vector<std::string> names_of(const EffectSetFit& fit) {
  std::vector<std::string> names;
  for (std::size_t c : fit.candidates) names.push_back(candidate_library()[c].name);
  return names;
}

}  // namespace

WorkflowResult run_discrepancy(const BenchData& recording, const WorkflowOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  auto progress = [&](const std::string& stage, double fraction) {
    if (options.progress) options.progress(stage, fraction);
  };
  if (!(options.fit_budget_s >= kMinFitBudget_s))
    throw DiscrepancyInputError("the fit budget must be at least " + std::to_string(static_cast<int>(kMinFitBudget_s)) +
                                " s (ten windows of 3 s spin-up and 5 s scored)");
  const nlohmann::json model = options.model.is_null() ? default_model() : options.model;
  // The fits score the windows' spans (fit_windows.hpp); without windows, everything.
  BenchData data = recording;
  const std::vector<RunWindow> windows = choose_fit_windows(data, options.fit_budget_s);
  for (const RunWindow& w : windows) data.fit_spans_s.emplace_back(w.score_from_s, w.end_s);
  Evaluator evaluator(model, options.model_source, data, options.threads);
  const std::vector<double> sigma = estimate_noise(data);
  double floor = 0.0;  // held-out cost of noise alone: 1 per assessed output
  for (std::size_t o = 0; o < data.outputs.size(); ++o) floor += assessable(sigma, o) ? 1.0 : 0.0;
  if (floor == 0.0)
    throw DiscrepancyInputError(data.source + ": no output's noise can be estimated from the data (too few samples, "
                                "or a sensor that never reads above 0)");
  const double total_fits = static_cast<double>(kRefined + 5);

  // Runs, recording seconds simulated and wall time per stage (report.json "stages").
  Json stages = Json::array();
  std::string stage_name;
  std::size_t stage_runs = 0;
  double stage_simulated_s = 0.0;
  auto stage_started = std::chrono::steady_clock::now();
  auto stage = [&](const std::string& name, double fraction) {
    const auto now = std::chrono::steady_clock::now();
    if (!stage_name.empty())
      stages.push_back({{"stage", stage_name},
                        {"model_runs", evaluator.runs() - stage_runs},
                        {"simulated_s", evaluator.simulated_s() - stage_simulated_s},
                        {"wall_time_s", std::chrono::duration<double>(now - stage_started).count()}});
    stage_name = name;
    stage_runs = evaluator.runs();
    stage_simulated_s = evaluator.simulated_s();
    stage_started = now;
    progress(name, fraction);
  };
  stage("the model as given", 0.0);
  WorkflowResult result;
  result.before = evaluator.run_baseline(windows, [&](double f) { progress("the model as given", f / total_fits); });
  if (!result.before.ok)
    throw DiscrepancyInputError(data.source + ": the model as given cannot follow this recording's hand motion (" +
                                result.before.failure + ")");
  const double cost_before = normalised_residuals(data, result.before, sigma, SampleSet::held_out).squaredNorm();
  // The candidates are compared on the held-out windows (all held-out data without windows).
  const double cost_before_fit = normalised_residuals(data, result.before, sigma, SampleSet::fit_held_out).squaredNorm();

  // Is there anything to explain?
  Json significance = Json::object();
  std::size_t most_affected = 0;
  double worst_ratio = -1.0;
  bool significant = false;
  for (std::size_t o = 0; o < data.outputs.size(); ++o) {
    const double rms = rms_error(data, result.before, o, SampleSet::held_out);
    if (!assessable(sigma, o)) {
      significance[output_name(data.outputs[o].id)] = {
          {"noise_sd", nullptr}, {"held_out_rms", rms}, {"assessed", false},
          {"why", "its noise cannot be estimated from the data (the sensor reads 0 nearly all the time)"}};
      continue;
    }
    const double ratio = rms / sigma[o];
    if (ratio > worst_ratio) {
      worst_ratio = ratio;
      most_affected = o;
    }
    significant = significant || ratio > options.significance;
    significance[output_name(data.outputs[o].id)] = {
        {"noise_sd", sigma[o]}, {"held_out_rms", rms}, {"assessed", true}, {"rms_over_noise", ratio},
        {"significant", ratio > options.significance}};
  }

  std::string verdict = "none";
  const EffectSetFit* chosen = nullptr;
  Json confirmation;  // windowed fits: the named effects' full run
  Json pair_test;     // the score test before pairs (when it ran)
  if (significant) {
    // 1. Screen every candidate (one Gauss-Newton step each from a shared Jacobian).
    stage("screening the candidates", 1.0 / total_fits);
    const std::vector<EffectSetFit> screened = screen_candidates(evaluator, data, result.before, sigma);
    result.candidates = screened;
    auto by_held_out = [](const EffectSetFit& a, const EffectSetFit& b) {
      if (a.ok != b.ok) return a.ok;
      return a.held_out_cost < b.held_out_cost;
    };
    std::sort(result.candidates.begin(), result.candidates.end(), by_held_out);
    auto share_of = [&](const EffectSetFit& f) {
      return f.ok ? share_explained(cost_before_fit, f.held_out_cost, floor) : 0.0;
    };
    // 2. Refine the best single effect; the next one while the refined ones explain too little,
    // or when its screening step came as close as kRefineNear (two effects that explain the same:
    // ei_profile with equal factors is ei_scale). Never one whose screening explained nothing.
    double best_refined_share = 0.0;
    for (std::size_t k = 0; k < std::min(kRefined, result.candidates.size()); ++k) {
      if (!result.candidates[k].ok) continue;
      if (k > 0 && !(share_of(result.candidates[k]) > 0.0)) break;
      if (k > 0 && best_refined_share >= options.min_share && share_of(result.candidates[k]) < best_refined_share - kRefineNear)
        break;
      const std::size_t c = result.candidates[k].candidates[0];
      stage("fitting " + candidate_library()[c].name, (2.0 + static_cast<double>(k)) / total_fits);
      const std::vector<double> start = result.candidates[k].values;
      const std::vector<nlohmann::json> held = result.candidates[k].held;
      EffectSetFit refined = fit_effect_set({c}, evaluator, data, result.before, sigma, &start, &held);
      if (refined.ok) result.candidates[k] = std::move(refined);
      best_refined_share = std::max(best_refined_share, share_of(result.candidates[k]));
    }
    std::sort(result.candidates.begin(), result.candidates.end(), by_held_out);
    // Ranked by held-out error, and by the information criterion among those within kTieShare
    // of the best: of two effects that explain the same, the one with fewer parameters leads.
    auto prefer_simpler = [&](std::vector<EffectSetFit>& fits) {
      if (fits.empty() || !fits.front().ok) return;
      std::size_t lead = 0;
      for (std::size_t k = 1; k < fits.size(); ++k)
        if (fits[k].ok && share_of(fits[k]) >= share_of(fits.front()) - kTieShare && fits[k].bic < fits[lead].bic) lead = k;
      std::rotate(fits.begin(), fits.begin() + static_cast<std::ptrdiff_t>(lead), fits.begin() + static_cast<std::ptrdiff_t>(lead) + 1);
    };
    prefer_simpler(result.candidates);
    auto leaves_nothing_significant = [&](const EffectSetFit& f) {
      for (std::size_t o = 0; o < data.outputs.size(); ++o)
        if (assessable(sigma, o) && rms_error(data, f.prediction, o, SampleSet::fit_held_out) / sigma[o] > options.significance)
          return false;
      return true;
    };
    const std::size_t best_single = 0;
    const bool single_explains = share_of(result.candidates[best_single]) >= options.min_share;
    std::optional<std::size_t> chosen_index;
    double partner_gain = 0.0;
    if (single_explains && !leaves_nothing_significant(result.candidates[best_single])) {
      double floor_training = 0.0;
      for (std::size_t o = 0; o < data.outputs.size(); ++o)
        floor_training += assessable(sigma, o) && samples_in_set(data, data.outputs[o], SampleSet::fit_training) > 0 ? 1.0 : 0.0;
      partner_gain = best_partner_gain(result.candidates[best_single], screened, data, sigma, floor_training);
      pair_test = {{"why", "the best single effect explains enough but leaves an output significant"},
                   {"best_partner_gain", partner_gain},
                   {"threshold", kMinPartnerGain},
                   {"pairs_tried", partner_gain >= kMinPartnerGain}};
    }
    if (single_explains &&
        (leaves_nothing_significant(result.candidates[best_single]) || partner_gain < kMinPartnerGain)) {
      chosen_index = best_single;
    } else if (share_of(result.candidates[best_single]) >= kMinSingleShareForPairs) {
      // 3. Pairs: ranked by the linearised joint step (no run), the best kPairs refined.
      const std::vector<PairEstimate> ranked = rank_pairs_linear(screened, result.before, data, sigma);
      // The pairs are fitted side by side: each fit's batches of runs leave threads idle that
      // the other's fill.
      const std::size_t pair_count = std::min(kPairs, ranked.size());
      std::string names;
      for (std::size_t k = 0; k < pair_count; ++k)
        names += (k > 0 ? ", " : "") + candidate_library()[screened[ranked[k].first].candidates[0]].name + " + " +
                 candidate_library()[screened[ranked[k].second].candidates[0]].name;
      stage("fitting " + names, (2.0 + static_cast<double>(kRefined)) / total_fits);
      std::vector<std::future<EffectSetFit>> pair_fits;
      for (std::size_t k = 0; k < pair_count; ++k) {
        const EffectSetFit& fa = screened[ranked[k].first];
        const EffectSetFit& fb = screened[ranked[k].second];
        std::vector<double> start;
        std::vector<nlohmann::json> held{fa.held[0], fb.held[0]};
        std::size_t at = 0;
        for (const EffectSetFit* f : {&fa, &fb}) {
          const std::vector<FittedParameter>& params = candidate_library()[f->candidates[0]].parameters;
          for (std::size_t j = 0; j < params.size(); ++j, ++at) {
            // Sigmoid mobility's angles come from its screening, not from the linear step.
            const bool angle = params[j].key.rfind("direction_", 0) == 0;
            const double value = angle ? f->values[j] : params[j].neutral + ranked[k].step[at];
            start.push_back(std::clamp(value, params[j].lo, params[j].hi));
          }
        }
        const std::vector<std::size_t> set{fa.candidates[0], fb.candidates[0]};
        // On windows (a long recording) two iterations: the start, the linearised joint step, is
        // close already, and the budget is the point of the windows.
        const int iterations = evaluator.windowed() ? 2 : 3;
        pair_fits.push_back(std::async(std::launch::async, [&evaluator, &data, &result, &sigma, set, start, held, iterations] {
          return fit_effect_set(set, evaluator, data, result.before, sigma, &start, &held, iterations);
        }));
      }
      std::vector<EffectSetFit> pairs;
      for (auto& f : pair_fits) pairs.push_back(f.get());
      // A pair whose member stayed at its neutral values is that member's partner alone (the
      // neutral effect changes nothing): it competes as a single effect.
      for (EffectSetFit& p : pairs) {
        if (!p.ok) continue;
        std::size_t at = 0;
        for (std::size_t k = 0; k < 2; ++k) {
          const Candidate& c = candidate_library()[p.candidates[k]];
          bool neutral = true;
          for (std::size_t j = 0; j < c.parameters.size(); ++j)
            if (c.parameters[j].key.rfind("direction_", 0) != 0 &&
                std::abs(p.values[at + j] - c.parameters[j].neutral) > 0.5 * c.parameters[j].step)
              neutral = false;
          if (neutral) {
            const std::size_t other = 1 - k;
            const std::size_t other_at = other == 0 ? 0 : candidate_library()[p.candidates[0]].parameters.size();
            const std::size_t n = candidate_library()[p.candidates[other]].parameters.size();
            EffectSetFit single;
            single.candidates = {p.candidates[other]};
            single.held = {p.held[other]};
            single.values.assign(p.values.begin() + static_cast<std::ptrdiff_t>(other_at),
                                 p.values.begin() + static_cast<std::ptrdiff_t>(other_at + n));
            single.effects = nlohmann::json::array({p.effects[other]});
            single.prediction = p.prediction;
            single.training_cost = p.training_cost;
            single.held_out_cost = p.held_out_cost;
            single.bic = bic_of(data, p.prediction, sigma, n);
            single.iterations = p.iterations;
            single.ok = true;
            p = std::move(single);
            break;
          }
          at += c.parameters.size();
        }
      }
      // Singles that came out of pairs replace the same effect's fit where they are better.
      for (auto it = pairs.begin(); it != pairs.end();) {
        if (it->candidates.size() == 1) {
          for (EffectSetFit& f : result.candidates)
            if (f.candidates == it->candidates && it->held_out_cost < f.held_out_cost) f = *it;
          it = pairs.erase(it);
        } else {
          ++it;
        }
      }
      std::sort(result.candidates.begin(), result.candidates.end(), by_held_out);
      prefer_simpler(result.candidates);
      std::sort(pairs.begin(), pairs.end(), by_held_out);
      const bool single_now_explains = share_of(result.candidates[best_single]) >= options.min_share;
      const EffectSetFit& single = result.candidates[best_single];
      const bool pair_better = !pairs.empty() && share_of(pairs.front()) >= options.min_share &&
                               pairs.front().bic < single.bic &&
                               share_of(pairs.front()) - share_of(single) >= kPairGain;
      // The list: the pairs (best first) ahead of the singles if the best pair is named, else
      // after them; the named set leads.
      if (pair_better) {
        result.candidates.insert(result.candidates.begin(), std::make_move_iterator(pairs.begin()),
                                 std::make_move_iterator(pairs.end()));
        chosen_index = 0;
      } else {
        for (EffectSetFit& p : pairs) result.candidates.push_back(std::move(p));
        if (single_now_explains) chosen_index = best_single;
      }
    }
    if (chosen_index) {
      verdict = "named";
      EffectSetFit& named = result.candidates[*chosen_index];
      stage(evaluator.windowed() ? "uncertainty, and the named effects over the whole recording"
                                 : "uncertainty of the named effects",
            1.0 - 1.0 / total_fits);
      if (evaluator.windowed()) {
        // The named effects over the whole recording (alongside the uncertainty's runs): every
        // before/after figure comes from full runs, and the verdict must hold there too.
        std::future<ModelPrediction> full =
            std::async(std::launch::async, [&] { return evaluator.run(named.effects, RunScope::full); });
        add_uncertainty(named, evaluator, data, sigma);
        ModelPrediction p = full.get();
        const double windows_cost = named.held_out_cost;
        const bool full_ok = p.ok;
        if (full_ok) {
          named.prediction = std::move(p);
          named.held_out_cost = normalised_residuals(data, named.prediction, sigma, SampleSet::held_out).squaredNorm();
        }
        const double full_share = full_ok ? share_explained(cost_before, named.held_out_cost, floor) : 0.0;
        confirmation = {{"held_out_cost_on_windows", windows_cost},
                        {"share_explained_on_windows", share_explained(cost_before_fit, windows_cost, floor)},
                        {"full_run_ok", full_ok},
                        {"full_run_failure", full_ok ? Json(nullptr) : Json(p.failure)},
                        {"held_out_cost_full", named.held_out_cost},
                        {"share_explained_full", full_share},
                        {"holds", full_share >= options.min_share}};
        if (full_share < options.min_share) {
          // Not confirmed over the whole recording: not named.
          verdict = "unexplained";
          named.held_out_cost = windows_cost;
        }
      } else {
        add_uncertainty(named, evaluator, data, sigma);
      }
      if (verdict == "named") chosen = &named;
    } else {
      verdict = "unexplained";
    }
  }
  stage("report", 1.0);
  result.after = chosen != nullptr ? chosen->prediction : result.before;

  // model.json: the input model with the named effects appended.
  result.model = model;
  if (chosen != nullptr) {
    nlohmann::json effects = result.model.contains("truth_effects") ? result.model["truth_effects"] : nlohmann::json::array();
    for (const auto& e : chosen->effects) effects.push_back(e);
    result.model["truth_effects"] = effects;
  }

  Json& r = result.report;
  r["recording"] = data.source;
  r["model"] = options.model_source;
  r["verdict"] = verdict;
  Json effects = Json::array();
  const double cost_after = chosen != nullptr ? chosen->held_out_cost : cost_before;
  if (chosen != nullptr) {
    for (std::size_t k = 0; k < chosen->candidates.size(); ++k) {
      const Candidate& c = candidate_library()[chosen->candidates[k]];
      double share = share_explained(cost_before, cost_after, floor);
      if (chosen->candidates.size() > 1) {
        // Its own share: what the pair explains beyond the other effect alone.
        for (const EffectSetFit& f : result.candidates)
          if (f.candidates.size() == 1 && f.candidates[0] != chosen->candidates[k])
            if (std::find(chosen->candidates.begin(), chosen->candidates.end(), f.candidates[0]) != chosen->candidates.end())
              share = share_explained(cost_before, cost_after, floor) -
                      share_explained(cost_before_fit, f.held_out_cost, floor);
      }
      Json regions = Json::array();
      const Json by_region = rmse_by_region(data, result.before, result.after);
      for (const auto& [region, outputs] : by_region.items()) {
        const Json& m = outputs.contains(output_name(data.outputs[most_affected].id)) ? outputs[output_name(data.outputs[most_affected].id)] : Json();
        if (!m.is_null() && m["before"].get<double>() > options.significance * sigma[most_affected] &&
            m["after"].get<double>() < 0.5 * m["before"].get<double>())
          regions.push_back(region);
      }
      effects.push_back({{"name", c.name},
                         {"parameters", effect_parameters(*chosen, k)},
                         {"where", {{"acts", c.acts}, {"regions_where_it_closes_the_gap", regions}}},
                         {"share_explained", share},
                         {"entry", chosen->effects[k]}});
    }
  }
  r["effects"] = effects;
  r["rmse_before"] = rmse_per_output(data, result.before, SampleSet::held_out);
  r["rmse_after"] = rmse_per_output(data, result.after, SampleSet::held_out);
  const double before_most = rms_error(data, result.before, most_affected, SampleSet::held_out);
  const double after_most = rms_error(data, result.after, most_affected, SampleSet::held_out);
  r["most_affected_output"] = {{"name", output_name(data.outputs[most_affected].id)},
                               {"held_out_rmse_before", before_most},
                               {"held_out_rmse_after", after_most},
                               {"reduction", before_most > 0 ? 1.0 - after_most / before_most : 0.0}};
  r["rmse_by_region"] = rmse_by_region(data, result.before, result.after);
  r["significance"] = {{"threshold_rms_over_noise", options.significance}, {"outputs", significance}};
  r["held_out"] = {{"blocks", kBlocks}, {"held_out_blocks", {1, 4, 7}},
                   {"rule", "the drive's span in 10 equal blocks; blocks 1, 4, 7 held out (residuals are autocorrelated)"}};
  Json candidates = Json::array();
  for (const EffectSetFit& f : result.candidates) {
    Json params = Json::array();
    if (f.ok)
      for (std::size_t k = 0; k < f.candidates.size(); ++k) params.push_back(effect_parameters(f, k));
    candidates.push_back({{"effects", names_of(f)},
                          {"ok", f.ok},
                          {"failure", f.ok ? Json(nullptr) : Json(f.failure)},
                          {"parameters", params},
                          {"training_cost", f.training_cost},
                          {"held_out_cost", f.held_out_cost},
                          {"bic", f.bic},
                          {"share_explained", f.ok ? share_explained(&f == chosen ? cost_before : cost_before_fit,
                                                                     f.held_out_cost, floor)
                                                   : 0.0},
                          {"iterations", f.iterations}});
  }
  r["candidates"] = candidates;
  r["pair_test"] = pair_test;
  r["baseline"] = {{"held_out_cost", cost_before}, {"noise_floor_cost", floor},
                   {"bic", bic_of(data, result.before, sigma, 0)}};
  r["location"] = locate(data, result.before, sigma, options.significance);
  r["recording_span_s"] = {data.start_s, data.end_s};
  Json window_list = Json::array();
  for (const RunWindow& w : windows)
    window_list.push_back({{"block", w.block}, {"start_s", w.start_s}, {"scored_from_s", w.score_from_s}, {"end_s", w.end_s}});
  r["fit_windows"] = {
      {"budget_s", options.fit_budget_s},
      {"windowed", !windows.empty()},
      {"rule", windows.empty() ? "the blocks fit the budget: every run covers the whole recording"
                               : "one window per block where the hand moves most, restarted from the baseline's state; "
                                 "the first " + std::to_string(windows.front().score_from_s - windows.front().start_s) +
                                     " s of each is spin-up, not scored; the candidates' costs are on these windows, "
                                     "before/after figures on full runs"},
      {"windows", window_list},
      {"confirmation", confirmation}};
  r["model_runs"] = evaluator.runs();
  r["simulated_s"] = evaluator.simulated_s();
  r["stages"] = stages;
  r["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace scopekin::discrepancy
