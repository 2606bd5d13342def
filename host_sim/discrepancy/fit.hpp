#pragma once
// Fitting a set of candidate effects (one, or a pair) to the training blocks: Levenberg-Marquardt
// on the normalised residual (analysis.hpp), from the neutral values, Jacobian by forward
// differences (each column one model run; columns run in parallel). Then the held-out cost, an
// information criterion and the parameters' uncertainty.
//
// Uncertainty. Cov = s^2 tau (J'^T J')^-1, J' the Jacobian of the residual in units of the noise
// (each sample weighted 1/sigma), s^2 = its mean square at the fit per degree of freedom, and
// tau = (1 + rho) / (1 - rho) for the lag-1 autocorrelation rho of the residual: neighbouring
// samples are not independent, and tau counts how many fewer independent ones there are.
// BIC = N ln(RSS' / N) + P ln(N) on the training samples (N components, P parameters).
#include <atomic>
#include <functional>
#include <utility>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/analysis.hpp"
#include "host_sim/discrepancy/candidates.hpp"

namespace scopekin::discrepancy {

/// What a run covers: the whole recording, or (with fit windows) the training windows, the
/// held-out ones, or all windows. Without windows every run is a full run.
enum class RunScope { full, fit_training, fit_held_out, fit_all };

/// Copies `from`'s outputs where it has them (not NaN) into `into`: the parts of a windowed run.
void merge_outputs(const ModelPrediction& from, ModelPrediction& into);

/// Runs the model with a list of effects (truth_effects entries); counts the runs; runs a batch
/// on up to `threads` threads (a windowed run alone is split over them by windows).
class Evaluator {
 public:
  Evaluator(nlohmann::json model, std::string model_source, const BenchData& data, unsigned threads);
  /// The model as given over the whole recording, saving the states the windows restart from
  /// (`windows` may be empty: no windows, every later run is full).
  ModelPrediction run_baseline(std::vector<RunWindow> windows, const std::function<void(double)>& progress = {});
  ModelPrediction run(const nlohmann::json& effects, RunScope scope = RunScope::fit_all) const;
  std::vector<ModelPrediction> run_all(const std::vector<nlohmann::json>& effect_lists,
                                       RunScope scope = RunScope::fit_all) const;
  std::vector<ModelPrediction> run_all(const std::vector<std::pair<nlohmann::json, RunScope>>& requests) const;
  std::size_t runs() const { return runs_.load(); }
  /// Recording seconds simulated by all runs so far.
  double simulated_s() const { return static_cast<double>(simulated_steps_.load()) * h_s_; }
  bool windowed() const { return !windows_.empty(); }
  const std::vector<RunWindow>& windows() const { return windows_; }
  const nlohmann::json& model() const { return model_; }

 private:
  ModelPrediction run_part(const nlohmann::json& effects, RunScope scope, const std::vector<std::size_t>& which) const;

  nlohmann::json model_;
  std::string source_;
  const BenchData& data_;
  unsigned threads_;
  std::vector<RunWindow> windows_;
  std::vector<model::World::State> states_;
  double h_s_ = 0.01;
  mutable std::atomic<std::size_t> runs_{0};
  mutable std::atomic<std::size_t> simulated_steps_{0};
};

struct EffectSetFit {
  std::vector<std::size_t> candidates;  ///< indices into candidate_library()
  std::vector<nlohmann::json> held;     ///< per candidate
  std::vector<double> values;           ///< fitted parameters, candidates' in order
  std::vector<double> sd;               ///< their standard deviations
  nlohmann::json effects = nlohmann::json::array();  ///< truth_effects entries at the fit
  ModelPrediction prediction;           ///< the model at the fit
  double training_cost = 0;             ///< |normalised residual|^2 on the training blocks
  double held_out_cost = 0;             ///< and on the held-out blocks
  double bic = 0;
  std::size_t iterations = 0;
  /// Screening only: the residual's Jacobian w.r.t. the parameters at the neutral point.
  Eigen::MatrixXd neutral_jacobian;
  bool ok = false;
  std::string failure;
};

/// Fits the candidates `set` (indices into candidate_library()). `baseline`: the model without
/// them (for held parameters read off the residual, and the neutral start). `start`: fitted
/// values to start from instead of the neutral ones (the candidates' parameters in order);
/// `held`: held parameters to use instead of the candidates' own (one per candidate).
EffectSetFit fit_effect_set(const std::vector<std::size_t>& set, const Evaluator& evaluator, const BenchData& data,
                            const ModelPrediction& baseline, const std::vector<double>& sigma,
                            const std::vector<double>* start = nullptr, const std::vector<nlohmann::json>* held = nullptr,
                            int max_iterations = 3);

/// Screening: every candidate of the library gets one Gauss-Newton step from its neutral values,
/// with the Jacobian of all their parameters computed at the baseline (one run per parameter,
/// in parallel), and one run at the step. Returns one fit per candidate (library order; no SDs).
std::vector<EffectSetFit> screen_candidates(const Evaluator& evaluator, const BenchData& data,
                                            const ModelPrediction& baseline, const std::vector<double>& sigma);

/// Standard deviations of a fit's parameters (the header's formula; P more runs).
void add_uncertainty(EffectSetFit& fit, const Evaluator& evaluator, const BenchData& data, const std::vector<double>& sigma);

/// A pair of screened candidates ranked by the training cost the linearised model predicts for
/// their joint Gauss-Newton step from the neutral point (no model run).
struct PairEstimate {
  std::size_t first = 0, second = 0;  ///< indices into the screened list
  double linear_training_cost = 0;
  std::vector<double> step;           ///< the joint step, first's parameters then second's
};
std::vector<PairEstimate> rank_pairs_linear(const std::vector<EffectSetFit>& screened, const ModelPrediction& baseline,
                                            const BenchData& data, const std::vector<double>& sigma);

/// Would a second effect help a fitted single one? A score test without runs: for each other
/// screened candidate, the training cost its neutral Jacobian predicts when its parameters are
/// added to the single's fitted residual (linear least squares). Returns the largest predicted
/// cost reduction as a fraction of the single's excess training cost (its cost above
/// `noise_floor_cost`, what noise alone gives), 0 when there is no excess.
double best_partner_gain(const EffectSetFit& single, const std::vector<EffectSetFit>& screened, const BenchData& data,
                         const std::vector<double>& sigma, double noise_floor_cost);

/// The BIC of a prediction with P fitted parameters (the baseline: P = 0).
double bic_of(const BenchData& data, const ModelPrediction& p, const std::vector<double>& sigma, std::size_t parameters);

}  // namespace scopekin::discrepancy
