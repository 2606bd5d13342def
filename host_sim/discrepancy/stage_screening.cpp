#include <algorithm>
#include <cmath>
#include <utility>

#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {
namespace {

/// sigmoid_mobility's direction: the load u sin(w t) + v cos(w t) is linear in (u, v); six runs
/// (unit load along x, y, z, sine and cosine) give its Jacobian, least squares the 6-vector, and
/// the SVD of [u v] the best single direction d with u = a d, v = b d.
struct SigmoidFit {
    bool ok = false;
    Eigen::Vector3d direction = Eigen::Vector3d::UnitY();
    double a = 0, b = 0;
    /// Columns for (A cos phi, A sin phi) along the direction, and zero columns for its angles
    /// (the angles do nothing at zero amplitude): the neutral Jacobian of the four parameters.
    Eigen::MatrixXd jacobian_along_direction;
};

SigmoidFit fit_sigmoid_direction(const DiscrepancyContext& context, const nlohmann::json& held,
                                 const Eigen::VectorXd& r0) {
    const Candidate* sigmoid = nullptr;
    for (const Candidate& c : candidate_library())
        if (c.name == "sigmoid_mobility") sigmoid = &c;
    SigmoidFit out;
    if (sigmoid == nullptr) return out;
    const double step = sigmoid->parameters[0].step;
    std::vector<nlohmann::json> lists;
    for (int axis = 0; axis < 3; ++axis)
        for (int part = 0; part < 2; ++part) {
            // Unit direction along the axis as polar / azimuth angles.
            const double polar = axis == 2 ? 0.0 : M_PI / 2.0;
            const double azimuth = axis == 1 ? M_PI / 2.0 : 0.0;
            lists.push_back(nlohmann::json::array(
                {sigmoid->entry(part == 0 ? std::vector<double>{step, 0.0, polar, azimuth}
                                          : std::vector<double>{0.0, step, polar, azimuth},
                                held)}));
        }
    const std::vector<ModelPrediction> runs =
        context.evaluator.run_all(lists, RunScope::fit_training);
    Eigen::MatrixXd J(r0.size(), 6);
    for (int k = 0; k < 6; ++k) {
        if (!runs[static_cast<std::size_t>(k)].ok) return out;
        // Column order: (u_x, v_x, u_y, v_y, u_z, v_z).
        J.col(k) =
            (context.residuals(runs[static_cast<std::size_t>(k)], SampleSet::fit_training) - r0) /
            step;
    }
    Eigen::MatrixXd A = J.transpose() * J;
    for (Eigen::Index k = 0; k < 6; ++k)
        A(k, k) += 1e-9 + 1e-6 * A(k, k);
    const Eigen::VectorXd w = A.ldlt().solve(-J.transpose() * r0);
    Eigen::Matrix<double, 3, 2> M;
    for (int axis = 0; axis < 3; ++axis) {
        M(axis, 0) = w[2 * axis];
        M(axis, 1) = w[2 * axis + 1];
    }
    Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
    if (!(svd.singularValues()[0] > 0.0)) return out;
    out.direction = svd.matrixU().col(0);
    Eigen::Index k = 0;
    out.direction.cwiseAbs().maxCoeff(&k);
    const double sign = out.direction[k] < 0.0 ? -1.0 : 1.0;
    out.direction *= sign;
    out.a = sign * svd.singularValues()[0] * svd.matrixV()(0, 0);
    out.b = sign * svd.singularValues()[0] * svd.matrixV()(1, 0);
    out.jacobian_along_direction = Eigen::MatrixXd::Zero(r0.size(), 4);
    for (int axis = 0; axis < 3; ++axis) {
        out.jacobian_along_direction.col(0) += out.direction[axis] * J.col(2 * axis);
        out.jacobian_along_direction.col(1) += out.direction[axis] * J.col(2 * axis + 1);
    }
    out.a = std::clamp(out.a, sigmoid->parameters[0].lo, sigmoid->parameters[0].hi);
    out.b = std::clamp(out.b, sigmoid->parameters[1].lo, sigmoid->parameters[1].hi);
    out.ok = true;
    return out;
}

/// The runs of the screening's shared forward-difference Jacobian: one per parameter of every
/// candidate but sigmoid_mobility (fit_sigmoid_direction), each from its neutral values.
struct NeutralColumns {
    std::vector<nlohmann::json> lists;
    std::vector<std::pair<std::size_t, std::size_t>> column_of;  // (candidate, parameter)
    std::vector<double> steps;
};

/// Starts every candidate's fit at its neutral values; returns the Jacobian's runs.
NeutralColumns neutral_columns(const DiscrepancyContext& context, std::vector<EffectSetFit>& fits) {
    const std::vector<Candidate>& library = candidate_library();
    NeutralColumns n;
    for (std::size_t c = 0; c < library.size(); ++c) {
        fits[c].candidates = {c};
        fits[c].held = {library[c].held(context.data, context.baseline)};
        std::vector<double> x;
        for (const FittedParameter& p : library[c].parameters)
            x.push_back(p.neutral);
        fits[c].values = x;
        if (library[c].name == "sigmoid_mobility")
            continue;  // its own runs (fit_sigmoid_direction)
        for (std::size_t j = 0; j < x.size(); ++j) {
            std::vector<double> xj = x;
            const FittedParameter& p = library[c].parameters[j];
            const double h = p.neutral + p.step <= p.hi ? p.step : -p.step;
            xj[j] += h;
            n.lists.push_back(nlohmann::json::array({library[c].entry(xj, fits[c].held[0])}));
            n.column_of.emplace_back(c, j);
            n.steps.push_back(h);
        }
    }
    return n;
}

/// The trials: each candidate's Gauss-Newton step from its Jacobian columns (sigmoid_mobility's
/// from fit_sigmoid_direction), as truth_effects lists, with the candidate each is for.
struct Trials {
    std::vector<nlohmann::json> lists;
    std::vector<std::size_t> of;
};

Trials gauss_newton_steps(const DiscrepancyContext& context, const NeutralColumns& n,
                          const std::vector<ModelPrediction>& columns, const Eigen::VectorXd& r0,
                          std::vector<EffectSetFit>& fits) {
    const std::vector<Candidate>& library = candidate_library();
    Trials trials;
    for (std::size_t c = 0; c < library.size(); ++c) {
        const std::size_t P = library[c].parameters.size();
        Eigen::MatrixXd J(r0.size(), static_cast<Eigen::Index>(P));
        bool ok = true;
        for (std::size_t k = 0; k < columns.size(); ++k) {
            if (n.column_of[k].first != c) continue;
            if (!columns[k].ok) {
                ok = false;
                fits[c].failure = "the run for the Jacobian failed: " + columns[k].failure;
                break;
            }
            J.col(static_cast<Eigen::Index>(n.column_of[k].second)) =
                (context.residuals(columns[k], SampleSet::fit_training) - r0) / n.steps[k];
        }
        if (!ok) continue;
        if (library[c].name == "sigmoid_mobility") {
            const SigmoidFit sf = fit_sigmoid_direction(context, fits[c].held[0], r0);
            if (sf.ok) {
                fits[c].neutral_jacobian = sf.jacobian_along_direction;
                fits[c].values = {sf.a, sf.b, std::acos(std::clamp(sf.direction.z(), -1.0, 1.0)),
                                  std::atan2(sf.direction.y(), sf.direction.x())};
                trials.lists.push_back(
                    nlohmann::json::array({library[c].entry(fits[c].values, fits[c].held[0])}));
                trials.of.push_back(c);
                continue;
            }
        }
        fits[c].neutral_jacobian = J;
        Eigen::MatrixXd A = J.transpose() * J;
        for (Eigen::Index k = 0; k < A.rows(); ++k)
            A(k, k) += 1e-9 + 1e-6 * A(k, k);
        const Eigen::VectorXd delta = A.ldlt().solve(-J.transpose() * r0);
        for (std::size_t j = 0; j < P; ++j)
            fits[c].values[j] =
                std::clamp(fits[c].values[j] + delta[static_cast<Eigen::Index>(j)],
                           library[c].parameters[j].lo, library[c].parameters[j].hi);
        trials.lists.push_back(
            nlohmann::json::array({library[c].entry(fits[c].values, fits[c].held[0])}));
        trials.of.push_back(c);
    }
    return trials;
}

}  // namespace

std::vector<EffectSetFit> screen_candidates(const DiscrepancyContext& context) {
    const Eigen::VectorXd r0 = context.residuals(context.baseline, SampleSet::fit_training);
    std::vector<EffectSetFit> fits(candidate_library().size());
    const NeutralColumns n = neutral_columns(context, fits);
    const std::vector<ModelPrediction> columns =
        context.evaluator.run_all(n.lists, RunScope::fit_training);
    const Trials trial_lists = gauss_newton_steps(context, n, columns, r0, fits);
    const std::vector<ModelPrediction> trials =
        context.evaluator.run_all(trial_lists.lists, RunScope::fit_all);
    for (std::size_t k = 0; k < trials.size(); ++k) {
        EffectSetFit& f = fits[trial_lists.of[k]];
        f.iterations = 1;
        f.effects = trial_lists.lists[k];
        f.prediction = trials[k];
        f.ok = trials[k].ok;
        if (!f.ok) {
            f.failure = trials[k].failure;
            continue;
        }
        f.training_cost = context.residuals(f.prediction, SampleSet::fit_training).squaredNorm();
        f.held_out_cost = context.residuals(f.prediction, SampleSet::fit_held_out).squaredNorm();
        f.bic = bic_of(context, f.prediction, f.values.size());
    }
    return fits;
}

}  // namespace scopekin::discrepancy
