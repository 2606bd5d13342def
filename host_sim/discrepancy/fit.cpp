#include "host_sim/discrepancy/fit.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace scopekin::discrepancy {

Eigen::VectorXd sqrt_counts(const MeasuredRecording& data, const std::vector<double>& sigma,
                            SampleSet set) {
    std::vector<double> s;
    for (std::size_t o = 0; o < data.outputs.size(); ++o) {
        if (!assessable(sigma, o)) continue;
        const MeasuredSeries& m = data.outputs[o];
        const std::size_t n = samples_in_set(data, m, set);
        for (std::size_t i = 0; i < n * static_cast<std::size_t>(m.components); ++i)
            s.push_back(std::sqrt(static_cast<double>(n)));
    }
    return Eigen::Map<const Eigen::VectorXd>(s.data(), static_cast<Eigen::Index>(s.size()));
}

namespace {

/// The runs of a forward-difference Jacobian at x: one per parameter, stepped by its `step`
/// (backwards where that would leave the bounds).
struct DifferenceRuns {
    std::vector<nlohmann::json> lists;
    std::vector<double> h;
};
DifferenceRuns forward_differences(
    const std::vector<double>& x, const std::vector<FittedParameter>& params,
    const std::function<nlohmann::json(const std::vector<double>&)>& entries) {
    DifferenceRuns d;
    for (std::size_t j = 0; j < params.size(); ++j) {
        std::vector<double> xj = x;
        d.h.push_back(xj[j] + params[j].step <= params[j].hi ? params[j].step : -params[j].step);
        xj[j] += d.h.back();
        d.lists.push_back(entries(xj));
    }
    return d;
}

struct Point {
    std::vector<double> x;
    ModelPrediction prediction;
    Eigen::VectorXd r;
    double cost = std::numeric_limits<double>::infinity();
};

/// A point of the fit: parameter values, the model run there and its training residual.
Point make_point(const DiscrepancyContext& context, std::vector<double> x, ModelPrediction p) {
    Point pt;
    pt.x = std::move(x);
    pt.prediction = std::move(p);
    if (pt.prediction.ok) {
        pt.r = context.residuals(pt.prediction, SampleSet::fit_training);
        pt.cost = pt.r.squaredNorm();
    }
    return pt;
}

/// One Levenberg-Marquardt iteration from `current`: the Jacobian (one run per parameter), then
/// up to three steps, damped more after each that does not lower the cost. Returns whether to
/// iterate again: not after a failed Jacobian run (`failure` says so), no accepted step, a step
/// below 1 % of the parameters' steps, or a negligible gain (converged).
bool iterate(const EffectSetFit& fit, const std::vector<FittedParameter>& params,
             const DiscrepancyContext& context, Point& current, double& lambda,
             std::string& failure) {
    const std::size_t P = params.size();
    auto entries = [&](const std::vector<double>& x) { return entries_of(fit, x); };
    // Jacobian columns.
    const DifferenceRuns differences = forward_differences(current.x, params, entries);
    const std::vector<double>& h = differences.h;
    const std::vector<ModelPrediction> columns =
        context.evaluator.run_all(differences.lists, RunScope::fit_training);
    Eigen::MatrixXd J(current.r.size(), static_cast<Eigen::Index>(P));
    for (std::size_t j = 0; j < P; ++j) {
        if (!columns[j].ok) {
            failure = "a model run for the Jacobian failed";
            return false;
        }
        J.col(static_cast<Eigen::Index>(j)) =
            (context.residuals(columns[j], SampleSet::fit_training) - current.r) / h[j];
    }
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * current.r;
    bool accepted = false;
    bool converged = false;
    double relative_step = 0.0;
    for (int attempt = 0; attempt < 3 && !accepted; ++attempt) {
        Eigen::MatrixXd A = JtJ;
        for (Eigen::Index k = 0; k < A.rows(); ++k)
            A(k, k) += lambda * std::max(JtJ(k, k), 1e-12);
        const Eigen::VectorXd delta = A.ldlt().solve(-g);
        std::vector<double> x = current.x;
        relative_step = 0.0;
        for (std::size_t j = 0; j < P; ++j) {
            x[j] =
                std::clamp(x[j] + delta[static_cast<Eigen::Index>(j)], params[j].lo, params[j].hi);
            relative_step = std::max(relative_step, std::abs(x[j] - current.x[j]) / params[j].step);
        }
        Point trial =
            make_point(context, x, context.evaluator.run(entries(x), RunScope::fit_training));
        if (trial.cost < current.cost) {
            const double gain = current.cost - trial.cost;
            current = std::move(trial);
            lambda = std::max(lambda / 4.0, 1e-6);
            accepted = true;
            converged = gain < 1e-3 * current.cost;
        } else {
            lambda *= 8.0;
        }
    }
    return accepted && !(relative_step < 0.01) && !converged;
}

}  // namespace

nlohmann::json entries_of(const EffectSetFit& fit, const std::vector<double>& x) {
    nlohmann::json list = nlohmann::json::array();
    std::size_t at = 0;
    for (std::size_t k = 0; k < fit.candidates.size(); ++k) {
        const Candidate& c = candidate_library()[fit.candidates[k]];
        const std::vector<double> v(
            x.begin() + static_cast<std::ptrdiff_t>(at),
            x.begin() + static_cast<std::ptrdiff_t>(at + c.parameters.size()));
        list.push_back(c.entry(v, fit.held[k]));
        at += c.parameters.size();
    }
    return list;
}

std::vector<FittedParameter> parameters_of(const EffectSetFit& fit) {
    std::vector<FittedParameter> params;
    for (std::size_t c : fit.candidates)
        for (const FittedParameter& p : candidate_library()[c].parameters)
            params.push_back(p);
    return params;
}

double bic_of(const DiscrepancyContext& context, const ModelPrediction& p, std::size_t parameters) {
    const Eigen::VectorXd r =
        context.residuals(p, SampleSet::fit_training)
            .cwiseProduct(sqrt_counts(context.data, context.sigma, SampleSet::fit_training));
    const double n = static_cast<double>(std::max<Eigen::Index>(r.size(), 1));
    return n * std::log(std::max(r.squaredNorm(), 1e-300) / n) +
           static_cast<double>(parameters) * std::log(n);
}

std::vector<std::string> names_of(const EffectSetFit& fit) {
    std::vector<std::string> names;
    for (std::size_t c : fit.candidates)
        names.push_back(candidate_library()[c].name);
    return names;
}

std::string set_name(const EffectSetFit& fit) {
    std::string name;
    for (const std::string& n : names_of(fit))
        name += (name.empty() ? "" : " + ") + n;
    return name;
}

std::vector<std::vector<double>> screen_grid(const std::vector<FittedParameter>& params,
                                             bool coarse) {
    std::vector<std::vector<double>> axes;
    for (const FittedParameter& p : params) {
        if (p.screen.empty()) return {};
        std::vector<double> axis{p.neutral};
        const std::size_t every = coarse && p.screen.size() > kCoarseAbove ? 2 : 1;
        for (std::size_t k = 0; k < p.screen.size(); k += every) {
            const double v = p.screen[k];
            if (v >= p.lo && v <= p.hi && v != p.neutral) axis.push_back(v);
        }
        axes.push_back(std::move(axis));
    }
    if (axes.empty()) return {};
    // Odometer order over the axes, each starting at its neutral value: the all-neutral point first.
    std::vector<std::vector<double>> points;
    std::vector<std::size_t> at(axes.size(), 0);
    for (;;) {
        std::vector<double> x;
        for (std::size_t j = 0; j < axes.size(); ++j)
            x.push_back(axes[j][at[j]]);
        points.push_back(std::move(x));
        std::size_t j = 0;
        while (j < axes.size() && ++at[j] == axes[j].size())
            at[j++] = 0;
        if (j == axes.size()) break;
    }
    return points;
}

std::vector<double> profile_dips(const std::vector<std::pair<double, double>>& profile) {
    std::vector<std::pair<double, double>> dips;  // (cost, value)
    for (std::size_t k = 0; k < profile.size() && profile.size() > 1; ++k) {
        const double cost = profile[k].second;
        const bool below_left = k == 0 || cost < profile[k - 1].second;
        const bool below_right = k + 1 == profile.size() || cost < profile[k + 1].second;
        if (std::isfinite(cost) && below_left && below_right)
            dips.emplace_back(cost, profile[k].first);
    }
    std::sort(dips.begin(), dips.end());
    std::vector<double> values;
    for (const auto& d : dips)
        values.push_back(d.second);
    return values;
}

GridScreen summarise_grid(const std::vector<FittedParameter>& params,
                          std::vector<std::vector<double>> points, std::vector<double> costs) {
    GridScreen g;
    g.points = std::move(points);
    g.costs = std::move(costs);
    g.costs.resize(g.points.size(), std::numeric_limits<double>::infinity());
    for (std::size_t k = 1; k < g.points.size(); ++k)
        if (g.costs[k] < g.costs[g.best]) g.best = k;
    g.profile.resize(params.size());
    for (std::size_t j = 0; j < params.size(); ++j) {
        std::vector<std::pair<double, double>>& prof = g.profile[j];
        for (std::size_t k = 0; k < g.points.size(); ++k) {
            const double v = g.points[k][j];
            auto it =
                std::find_if(prof.begin(), prof.end(),
                             [v](const std::pair<double, double>& e) { return e.first == v; });
            if (it == prof.end())
                prof.emplace_back(v, g.costs[k]);
            else
                it->second = std::min(it->second, g.costs[k]);
        }
        std::sort(prof.begin(), prof.end());
    }
    return g;
}

EffectSetFit fit_effect_set(const std::vector<std::size_t>& set, const DiscrepancyContext& context,
                            const std::vector<double>* start,
                            const std::vector<nlohmann::json>* held, int max_iterations) {
    const std::vector<Candidate>& library = candidate_library();
    const Evaluator& evaluator = context.evaluator;
    EffectSetFit fit;
    fit.candidates = set;
    for (std::size_t k = 0; k < set.size(); ++k) {
        const std::size_t c = set[k];
        fit.held.push_back(held != nullptr && held->size() == set.size()
                               ? (*held)[k]
                               : library[c].held(context.data, context.baseline));
    }
    const std::vector<FittedParameter> params = parameters_of(fit);
    const std::size_t P = params.size();
    std::vector<double> x0;
    for (const FittedParameter& p : params)
        x0.push_back(p.neutral);
    // The neutral point is the baseline itself (the effects vanish there).
    Point current = make_point(context, x0, context.baseline);
    if (start != nullptr && start->size() == P && *start != x0) {
        Point from = make_point(context, *start,
                                evaluator.run(entries_of(fit, *start), RunScope::fit_training));
        if (from.cost < current.cost) current = std::move(from);
    }
    double lambda = 1e-2;
    for (int it = 0; it < max_iterations; ++it) {
        fit.iterations = static_cast<std::size_t>(it + 1);
        if (!iterate(fit, params, context, current, lambda, fit.failure)) break;
    }

    fit.values = current.x;
    fit.effects = entries_of(fit, current.x);
    fit.prediction = current.prediction;
    fit.ok = current.prediction.ok;
    if (!fit.ok) {
        if (fit.failure.empty()) fit.failure = current.prediction.failure;
        return fit;
    }
    if (evaluator.windowed() && current.x != x0) {
        // The trials ran the training windows only: the held-out windows at the fit.
        const ModelPrediction held_out = evaluator.run(fit.effects, RunScope::fit_held_out);
        if (!held_out.ok) {
            fit.ok = false;
            fit.failure = held_out.failure;
            return fit;
        }
        merge_outputs(held_out, fit.prediction);
    }
    fit.training_cost = current.cost;
    fit.held_out_cost = context.residuals(fit.prediction, SampleSet::fit_held_out).squaredNorm();
    fit.bic = bic_of(context, fit.prediction, P);
    return fit;
}

double valley_variance(const EffectSetFit& fit, const std::vector<FittedParameter>& params,
                       double chi2_at_fit, double s2) {
    const nlohmann::ordered_json& walk = fit.valley_walk;
    if (!walk.is_object() || !walk.contains("floor") || !walk.contains("along"))
        return std::numeric_limits<double>::quiet_NaN();
    std::size_t q = params.size();
    for (std::size_t j = 0; j < params.size(); ++j)
        if (params[j].key == walk["along"].get<std::string>()) q = j;
    if (q == params.size()) return std::numeric_limits<double>::quiet_NaN();
    double rise_d2 = 0.0, d4 = 0.0;
    for (const auto& point : walk["floor"]) {
        const double d = point["values"][q].get<double>() - fit.values[q];
        const double rise = std::max(0.0, point["training_chi2"].get<double>() - chi2_at_fit);
        rise_d2 += rise * d * d;
        d4 += d * d * d * d;
    }
    if (!(d4 > 0.0) || !(rise_d2 > 0.0)) return std::numeric_limits<double>::quiet_NaN();
    return s2 * d4 / rise_d2;
}

void add_uncertainty(EffectSetFit& fit, const DiscrepancyContext& context) {
    const MeasuredRecording& data = context.data;
    const std::vector<double>& sigma = context.sigma;
    const std::vector<FittedParameter> params = parameters_of(fit);
    const std::size_t P = params.size();
    fit.sd.assign(P, std::numeric_limits<double>::quiet_NaN());
    fit.sd_unavailable.assign(P, "");
    if (!fit.ok) {
        fit.sd_unavailable.assign(P, "the fit did not complete: " + fit.failure);
        return;
    }
    // One more Jacobian at the fit, in plain 1/sigma weighting.
    const DifferenceRuns differences = forward_differences(
        fit.values, params, [&](const std::vector<double>& x) { return entries_of(fit, x); });
    const std::vector<double>& h = differences.h;
    const std::vector<ModelPrediction> columns =
        context.evaluator.run_all(differences.lists, RunScope::fit_training);
    const Eigen::VectorXd s = sqrt_counts(data, sigma, SampleSet::fit_training);
    const Eigen::VectorXd r0 =
        normalised_residuals(data, fit.prediction, sigma, SampleSet::fit_training);
    const Eigen::VectorXd r = r0.cwiseProduct(s);
    Eigen::MatrixXd J(r.size(), static_cast<Eigen::Index>(P));
    for (std::size_t j = 0; j < P; ++j) {
        if (!columns[j].ok) {
            fit.sd_unavailable.assign(P, "the model run for the Jacobian at the fit failed (" +
                                             params[j].key + " stepped): " + columns[j].failure);
            return;
        }
        J.col(static_cast<Eigen::Index>(j)) =
            (normalised_residuals(data, columns[j], sigma, SampleSet::fit_training) - r0)
                .cwiseProduct(s) /
            h[j];
    }
    const double n = static_cast<double>(r.size());
    double rho = 0.0;
    if (r.size() > 2)
        rho = r.head(r.size() - 1).dot(r.tail(r.size() - 1)) / std::max(r.squaredNorm(), 1e-300);
    rho = std::clamp(rho, 0.0, 0.99);
    const double s2 =
        r.squaredNorm() / std::max(1.0, n - static_cast<double>(P)) * (1.0 + rho) / (1.0 - rho);
    const Eigen::MatrixXd cov =
        (J.transpose() * J).completeOrthogonalDecomposition().pseudoInverse() * s2;
    const Eigen::MatrixXd jackknife = block_jackknife_covariance(context.training_rows, J, r);
    for (std::size_t j = 0; j < P; ++j) {
        // A parameter the training data do not respond to has no finite SD (the pseudo-inverse
        // would report 0, as if it were known exactly).
        if (!(J.col(static_cast<Eigen::Index>(j)).norm() > 0.0)) {
            fit.sd_unavailable[j] = "the training data do not respond to " + params[j].key +
                                    " at the fit (its Jacobian column is zero): not identified";
            continue;
        }
        const auto jj = static_cast<Eigen::Index>(j);
        // A valley the fit was walked along (walk_valley) says how far the parameter can move at
        // the least cost: its floor's width, not the curvature at the fit, where a narrow valley
        // reads as a tight bound on both parameters.
        const bool walked = fit.valley_walk.is_object() &&
                            params[j].key == fit.valley_walk["along"].get<std::string>();
        const double valley = walked ? valley_variance(fit, params, r.squaredNorm(), s2) : 0.0;
        fit.sd[j] =
            std::sqrt(std::max({0.0, cov(jj, jj), jackknife.size() > 0 ? jackknife(jj, jj) : 0.0,
                                std::isfinite(valley) ? valley : 0.0}));
    }
}

Eigen::MatrixXd block_jackknife_covariance(const BlockRows& rows, const Eigen::MatrixXd& J,
                                           const Eigen::VectorXd& r) {
    const Eigen::Index P = J.cols();
    if (static_cast<std::size_t>(J.rows()) != rows.block_of_row.size() || P == 0) return {};
    std::vector<Eigen::MatrixXd> H(kBlocks, Eigen::MatrixXd::Zero(P, P));
    std::vector<Eigen::VectorXd> g(kBlocks, Eigen::VectorXd::Zero(P));
    std::vector<bool> present(kBlocks, false);
    for (Eigen::Index k = 0; k < J.rows(); ++k) {
        const auto b = static_cast<std::size_t>(rows.block_of_row[static_cast<std::size_t>(k)]);
        H[b] += J.row(k).transpose() * J.row(k);
        g[b] += J.row(k).transpose() * r[k];
        present[b] = true;
    }
    Eigen::MatrixXd total = Eigen::MatrixXd::Zero(P, P);
    for (const Eigen::MatrixXd& h : H)
        total += h;
    std::vector<Eigen::VectorXd> moves;
    for (std::size_t b = 0; b < H.size(); ++b)
        if (present[b])
            moves.push_back((total - H[b]).completeOrthogonalDecomposition().pseudoInverse() *
                            g[b]);
    if (moves.size() < 3) return {};
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(P);
    for (const Eigen::VectorXd& m : moves)
        mean += m / static_cast<double>(moves.size());
    Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(P, P);
    for (const Eigen::VectorXd& m : moves)
        cov += (m - mean) * (m - mean).transpose();
    const double B = static_cast<double>(moves.size());
    return cov * ((B - 1.0) / B);
}

}  // namespace scopekin::discrepancy
