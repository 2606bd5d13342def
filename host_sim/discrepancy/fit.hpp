#pragma once
// Fitting a set of candidate effects (one, or a pair) to the training blocks: Levenberg-Marquardt
// on the normalised residual (analysis.hpp), from the neutral values, Jacobian by forward
// differences (each column one model run; columns run in parallel). Then the held-out cost, an
// information criterion and the parameters' uncertainty.
//
// Uncertainty. Cov = s^2 tau (J'^T J')^-1, J' the Jacobian of the residual in units of the noise
// (each sample weighted 1/sigma), s^2 = its mean square at the fit per degree of freedom, and
// tau = (1 + rho) / (1 - rho) for the lag-1 autocorrelation rho of the residual: neighbouring
// samples are not independent, and tau counts how many fewer independent ones there are. The SD
// reported is the larger of that and the training blocks' linearised jackknife (fit.cpp,
// block_jackknife_covariance): where a block's own structure (an event's timing, a misfit the
// effect cannot follow) drives the estimate, the residual is not noise, and the jackknife sees it.
// BIC = N ln(RSS' / N) + P ln(N) on the training samples (N components, P parameters).
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/candidates.hpp"
#include "host_sim/discrepancy/context.hpp"

namespace scopekin::discrepancy {

struct EffectSetFit {
    std::vector<std::size_t> candidates;  ///< indices into candidate_library()
    std::vector<nlohmann::json> held;     ///< per candidate
    std::vector<double> values;           ///< fitted parameters, candidates' in order
    std::vector<double> sd;               ///< their standard deviations
    /// Per parameter, why its SD could not be computed (empty where sd is finite).
    std::vector<std::string> sd_unavailable;
    nlohmann::json effects = nlohmann::json::array();  ///< truth_effects entries at the fit
    ModelPrediction prediction;                        ///< the model at the fit
    double training_cost = 0;  ///< |normalised residual|^2 on the training blocks
    double held_out_cost = 0;  ///< and on the held-out blocks
    double bic = 0;
    std::size_t iterations = 0;
    /// Screening only: the residual's Jacobian w.r.t. the parameters at the neutral point.
    Eigen::MatrixXd neutral_jacobian;
    /// Screening only, one-parameter candidates: the grid's training cost along the parameter's
    /// axis, (value, cost) by ascending value (the refinement's line search visits its dips).
    std::vector<std::pair<double, double>> screen_profile;
    /// Two-parameter candidates: the refinement's walk along the valley (walk_valley), else null.
    nlohmann::ordered_json valley_walk;
    bool ok = false;
    std::string failure;
};

/// Fits the candidates `set` (indices into candidate_library()), starting from the model as
/// given (the context's baseline: held parameters read off its residual, the neutral start).
/// `start`: fitted values to start from instead of the neutral ones (the candidates' parameters
/// in order); `held`: held parameters to use instead of the candidates' own (one per candidate).
EffectSetFit fit_effect_set(const std::vector<std::size_t>& set, const DiscrepancyContext& context,
                            const std::vector<double>* start = nullptr,
                            const std::vector<nlohmann::json>* held = nullptr,
                            int max_iterations = 3);

/// The truth_effects entries of a fit's set at values `x` (its candidates' parameters in order).
nlohmann::json entries_of(const EffectSetFit& fit, const std::vector<double>& x);
/// The fitted parameters of a fit's set, its candidates' in order.
std::vector<FittedParameter> parameters_of(const EffectSetFit& fit);

/// Per residual row, sqrt(n_o) of its output: turns the 1/(sigma sqrt(n)) weighting of
/// normalised_residuals into plain 1/sigma (chi-square residuals).
Eigen::VectorXd sqrt_counts(const MeasuredRecording& data, const std::vector<double>& sigma,
                            SampleSet set);

/// The variance of the parameter a fit's valley was walked along (walk_valley, `fit.valley_walk`)
/// from the valley's floor: the floor's rise in chi-square above the fit's (`chi2_at_fit`), fitted
/// by a (q - q_fit)^2 through the fit (least squares), is 1 / [(J^T J)^-1]_qq of the Gauss-Newton
/// model minimised over the other parameter, so the variance is s2 / a (`s2`: the residual
/// variance add_uncertainty scales the covariance by). NaN without a walk or without a rise.
double valley_variance(const EffectSetFit& fit, const std::vector<FittedParameter>& params,
                       double chi2_at_fit, double s2);

/// Standard deviations of a fit's parameters (the header's formula; P more runs). A parameter the
/// fit's valley was walked along (walk_valley) takes the larger of that and the valley floor's
/// width (the floor's chi-square rise fitted by a parabola through the fit).
void add_uncertainty(EffectSetFit& fit, const DiscrepancyContext& context);

/// The block jackknife of a least-squares fit, linearised (no runs): with training block b left
/// out, one Gauss-Newton step from the fit on the other blocks moves the parameters by
/// (H - H_b)^-1 J_b^T r_b (the full gradient J^T r is about 0 at the fit); the covariance is
/// (B - 1)/B times the scatter of those moves (Efron & Tibshirani, *An Introduction to the
/// Bootstrap*, 1993, ch. 11). `J` and `r` in the rows' order (rows.block_of_row). Residuals that a
/// block's own structure drives (an event's timing, a misfit the effect cannot follow) move the
/// estimate when their block is left out, and the noise formula above does not see them. Empty
/// when fewer than three blocks have rows.
Eigen::MatrixXd block_jackknife_covariance(const BlockRows& rows, const Eigen::MatrixXd& J,
                                           const Eigen::VectorXd& r);

/// The BIC of a prediction with P fitted parameters (the baseline: P = 0).
double bic_of(const DiscrepancyContext& context, const ModelPrediction& p, std::size_t parameters);

/// The candidates of a fit by name.
std::vector<std::string> names_of(const EffectSetFit& fit);
/// And as one name, "a + b" for a pair.
std::string set_name(const EffectSetFit& fit);

/// The screening's search over a candidate's range (README step 4): the tensor grid of its
/// parameters' `screen` values, each axis with its neutral value too, and what it found. No
/// derivatives: a training cost that steps with event timing (a stick-release that comes a
/// little earlier or later) cannot send it the wrong way, as it can a finite-difference step.
struct GridScreen {
    std::vector<std::vector<double>> points;  ///< every grid point, the all-neutral one first
    std::vector<double> costs;                ///< the cost at each (infinity: its run failed)
    std::size_t best = 0;                     ///< the lowest cost (the earliest of equals)
    /// Per parameter: each of its axis values with the lowest cost over the other parameters
    /// (the profile of the cost along the parameter's range).
    std::vector<std::vector<std::pair<double, double>>> profile;
};
/// The dips of a cost profile ((value, cost) by ascending value, as GridScreen::profile): the
/// values whose cost is below their neighbours' (an end below its one neighbour), lowest first.
std::vector<double> profile_dips(const std::vector<std::pair<double, double>>& profile);
/// The grid's points, the all-neutral one first; none when a parameter has no `screen`. `coarse`
/// (a recording fitted on windows, where each run is a long one): every other value of an axis
/// longer than kCoarseAbove, the first and the ×4 steps of a ×2 axis, to keep a 10-minute
/// recording within its 2-minute budget.
inline constexpr std::size_t kCoarseAbove = 5;
std::vector<std::vector<double>> screen_grid(const std::vector<FittedParameter>& params,
                                             bool coarse = false);
/// The best point and the profiles, from the costs of screen_grid(params)'s points in order.
GridScreen summarise_grid(const std::vector<FittedParameter>& params,
                          std::vector<std::vector<double>> points, std::vector<double> costs);

}  // namespace scopekin::discrepancy
