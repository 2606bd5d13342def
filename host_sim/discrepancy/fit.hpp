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
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/analysis.hpp"
#include "host_sim/discrepancy/candidates.hpp"

namespace scopekin::discrepancy {

/// Runs the model with a list of effects (truth_effects entries); counts the runs; runs a batch
/// on up to `threads` threads.
class Evaluator {
 public:
  Evaluator(nlohmann::json model, std::string model_source, const BenchData& data, unsigned threads);
  ModelPrediction run(const nlohmann::json& effects) const;
  std::vector<ModelPrediction> run_all(const std::vector<nlohmann::json>& effect_lists) const;
  std::size_t runs() const { return runs_.load(); }
  const nlohmann::json& model() const { return model_; }

 private:
  nlohmann::json model_;
  std::string source_;
  const BenchData& data_;
  unsigned threads_;
  mutable std::atomic<std::size_t> runs_{0};
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

/// The BIC of a prediction with P fitted parameters (the baseline: P = 0).
double bic_of(const BenchData& data, const ModelPrediction& p, const std::vector<double>& sigma, std::size_t parameters);

}  // namespace scopekin::discrepancy
