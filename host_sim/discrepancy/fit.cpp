#include "host_sim/discrepancy/fit.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <limits>

namespace scopekin::discrepancy {

Evaluator::Evaluator(nlohmann::json model, std::string model_source, const BenchData& data, unsigned threads)
    : model_(std::move(model)), source_(std::move(model_source)), data_(data), threads_(std::max(1U, threads)) {}

ModelPrediction Evaluator::run_baseline(std::vector<RunWindow> windows, const std::function<void(double)>& progress) {
  ++runs_;
  windows_ = std::move(windows);
  ModelPrediction p = predict(model_, source_, nlohmann::json::array(), data_, progress, &windows_, &states_);
  h_s_ = p.h_s;
  simulated_steps_ += p.steps;
  if (!p.ok) windows_.clear();
  return p;
}

ModelPrediction Evaluator::run_part(const nlohmann::json& effects, RunScope scope,
                                    const std::vector<std::size_t>& which) const {
  ModelPrediction p = scope == RunScope::full || !windowed()
                          ? predict(model_, source_, effects, data_)
                          : predict_windows(model_, source_, effects, data_, windows_, states_, which);
  simulated_steps_ += p.steps;
  return p;
}

ModelPrediction Evaluator::run(const nlohmann::json& effects, RunScope scope) const {
  return run_all(std::vector<std::pair<nlohmann::json, RunScope>>{{effects, scope}}).front();
}

std::vector<ModelPrediction> Evaluator::run_all(const std::vector<nlohmann::json>& lists, RunScope scope) const {
  std::vector<std::pair<nlohmann::json, RunScope>> requests;
  for (const nlohmann::json& l : lists) requests.emplace_back(l, scope);
  return run_all(requests);
}

std::vector<ModelPrediction> Evaluator::run_all(const std::vector<std::pair<nlohmann::json, RunScope>>& requests) const {
  // Tasks: a full run is one task; a windowed run is split by windows into as many parts as
  // leave no thread idle (one part each when there are at least as many runs as threads).
  struct Task {
    std::size_t request;
    std::vector<std::size_t> windows;
  };
  std::vector<Task> tasks;
  const std::size_t parts = std::max<std::size_t>(1, threads_ / std::max<std::size_t>(1, requests.size()));
  for (std::size_t r = 0; r < requests.size(); ++r) {
    ++runs_;
    if (requests[r].second == RunScope::full || !windowed()) {
      tasks.push_back({r, {}});
      continue;
    }
    std::vector<std::size_t> which;
    for (std::size_t w = 0; w < windows_.size(); ++w)
      if (requests[r].second == RunScope::fit_all ||
          is_held_out_block(windows_[w].block) == (requests[r].second == RunScope::fit_held_out))
        which.push_back(w);
    const std::size_t n = std::min(parts, which.size());
    for (std::size_t part = 0; part < n; ++part) {
      Task t{r, {}};
      for (std::size_t k = part; k < which.size(); k += n) t.windows.push_back(which[k]);
      tasks.push_back(std::move(t));
    }
  }
  std::vector<ModelPrediction> results(tasks.size());
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t k = next++; k < tasks.size(); k = next++)
      results[k] = run_part(requests[tasks[k].request].first, requests[tasks[k].request].second, tasks[k].windows);
  };
  std::vector<std::future<void>> workers;
  for (unsigned w = 0; w < std::min<std::size_t>(threads_, tasks.size()); ++w)
    workers.push_back(std::async(std::launch::async, worker));
  for (auto& w : workers) w.get();
  // Parts of one windowed run fill disjoint samples: merge them.
  std::vector<ModelPrediction> out(requests.size());
  std::vector<bool> seen(requests.size(), false);
  for (std::size_t k = 0; k < tasks.size(); ++k) {
    ModelPrediction& into = out[tasks[k].request];
    ModelPrediction& part = results[k];
    if (!seen[tasks[k].request]) {
      into = std::move(part);
      seen[tasks[k].request] = true;
      continue;
    }
    if (!into.ok) continue;
    if (!part.ok) {
      into = std::move(part);
      continue;
    }
    merge_outputs(part, into);
  }
  return out;
}

void merge_outputs(const ModelPrediction& from, ModelPrediction& into) {
  into.steps += from.steps;
  for (std::size_t o = 0; o < into.outputs.size() && o < from.outputs.size(); ++o)
    for (std::size_t i = 0; i < into.outputs[o].size(); ++i)
      if (!std::isnan(from.outputs[o][i].x())) into.outputs[o][i] = from.outputs[o][i];
}

namespace {

/// Per residual row, sqrt(n_o) of its output: turns the 1/(sigma sqrt(n)) weighting of
/// normalised_residuals into plain 1/sigma.
Eigen::VectorXd sqrt_counts(const BenchData& data, const std::vector<double>& sigma, SampleSet set) {
  std::vector<double> s;
  for (std::size_t o = 0; o < data.outputs.size(); ++o) {
    if (!assessable(sigma, o)) continue;
    const MeasuredSeries& m = data.outputs[o];
    const std::size_t n = samples_in_set(data, m, set);
    for (std::size_t i = 0; i < n * static_cast<std::size_t>(m.components); ++i) s.push_back(std::sqrt(static_cast<double>(n)));
  }
  return Eigen::Map<const Eigen::VectorXd>(s.data(), static_cast<Eigen::Index>(s.size()));
}

/// The runs of a forward-difference Jacobian at x: one per parameter, stepped by its `step`
/// (backwards where that would leave the bounds).
struct DifferenceRuns {
  std::vector<nlohmann::json> lists;
  std::vector<double> h;
};
DifferenceRuns forward_differences(const std::vector<double>& x, const std::vector<FittedParameter>& params,
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

}  // namespace

double bic_of(const BenchData& data, const ModelPrediction& p, const std::vector<double>& sigma, std::size_t parameters) {
  const Eigen::VectorXd r = normalised_residuals(data, p, sigma, SampleSet::fit_training)
                                .cwiseProduct(sqrt_counts(data, sigma, SampleSet::fit_training));
  const double n = static_cast<double>(std::max<Eigen::Index>(r.size(), 1));
  return n * std::log(std::max(r.squaredNorm(), 1e-300) / n) + static_cast<double>(parameters) * std::log(n);
}

namespace {

/// The truth_effects entries of a fit's set at values x.
nlohmann::json entries_of(const EffectSetFit& fit, const std::vector<double>& x) {
  nlohmann::json list = nlohmann::json::array();
  std::size_t at = 0;
  for (std::size_t k = 0; k < fit.candidates.size(); ++k) {
    const Candidate& c = candidate_library()[fit.candidates[k]];
    const std::vector<double> v(x.begin() + static_cast<std::ptrdiff_t>(at),
                                x.begin() + static_cast<std::ptrdiff_t>(at + c.parameters.size()));
    list.push_back(c.entry(v, fit.held[k]));
    at += c.parameters.size();
  }
  return list;
}

std::vector<FittedParameter> parameters_of(const EffectSetFit& fit) {
  std::vector<FittedParameter> params;
  for (std::size_t c : fit.candidates)
    for (const FittedParameter& p : candidate_library()[c].parameters) params.push_back(p);
  return params;
}

}  // namespace

EffectSetFit fit_effect_set(const std::vector<std::size_t>& set, const Evaluator& evaluator, const BenchData& data,
                            const ModelPrediction& baseline, const std::vector<double>& sigma,
                            const std::vector<double>* start, const std::vector<nlohmann::json>* held,
                            int max_iterations) {
  const std::vector<Candidate>& library = candidate_library();
  EffectSetFit fit;
  fit.candidates = set;
  for (std::size_t k = 0; k < set.size(); ++k) {
    const std::size_t c = set[k];
    fit.held.push_back(held != nullptr && held->size() == set.size() ? (*held)[k] : library[c].held(data, baseline));
  }
  const std::vector<FittedParameter> params = parameters_of(fit);
  const std::size_t P = params.size();
  auto entries = [&](const std::vector<double>& x) { return entries_of(fit, x); };
  auto make_point = [&](std::vector<double> x, ModelPrediction p) {
    Point pt;
    pt.x = std::move(x);
    pt.prediction = std::move(p);
    if (pt.prediction.ok) {
      pt.r = normalised_residuals(data, pt.prediction, sigma, SampleSet::fit_training);
      pt.cost = pt.r.squaredNorm();
    }
    return pt;
  };

  std::vector<double> x0;
  for (const FittedParameter& p : params) x0.push_back(p.neutral);
  // The neutral point is the baseline itself (the effects vanish there).
  Point current = make_point(x0, baseline);
  if (start != nullptr && start->size() == P && *start != x0) {
    Point from = make_point(*start, evaluator.run(entries(*start), RunScope::fit_training));
    if (from.cost < current.cost) current = std::move(from);
  }
  double lambda = 1e-2;
  for (int it = 0; it < max_iterations; ++it) {
    fit.iterations = static_cast<std::size_t>(it + 1);
    // Jacobian columns.
    const DifferenceRuns differences = forward_differences(current.x, params, entries);
    const std::vector<double>& h = differences.h;
    const std::vector<ModelPrediction> columns = evaluator.run_all(differences.lists, RunScope::fit_training);
    Eigen::MatrixXd J(current.r.size(), static_cast<Eigen::Index>(P));
    bool usable = true;
    for (std::size_t j = 0; j < P; ++j) {
      if (!columns[j].ok) {
        usable = false;
        break;
      }
      J.col(static_cast<Eigen::Index>(j)) =
          (normalised_residuals(data, columns[j], sigma, SampleSet::fit_training) - current.r) / h[j];
    }
    if (!usable) {
      fit.failure = "a model run for the Jacobian failed";
      break;
    }
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * current.r;
    bool accepted = false;
    double relative_step = 0.0;
    for (int attempt = 0; attempt < 3 && !accepted; ++attempt) {
      Eigen::MatrixXd A = JtJ;
      for (Eigen::Index k = 0; k < A.rows(); ++k) A(k, k) += lambda * std::max(JtJ(k, k), 1e-12);
      const Eigen::VectorXd delta = A.ldlt().solve(-g);
      std::vector<double> x = current.x;
      relative_step = 0.0;
      for (std::size_t j = 0; j < P; ++j) {
        x[j] = std::clamp(x[j] + delta[static_cast<Eigen::Index>(j)], params[j].lo, params[j].hi);
        relative_step = std::max(relative_step, std::abs(x[j] - current.x[j]) / params[j].step);
      }
      Point trial = make_point(x, evaluator.run(entries(x), RunScope::fit_training));
      if (trial.cost < current.cost) {
        const double gain = current.cost - trial.cost;
        current = std::move(trial);
        lambda = std::max(lambda / 4.0, 1e-6);
        accepted = true;
        if (gain < 1e-3 * current.cost) it = max_iterations;  // converged
      } else {
        lambda *= 8.0;
      }
    }
    if (!accepted || relative_step < 0.01) break;
  }

  fit.values = current.x;
  fit.effects = entries(current.x);
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
  fit.held_out_cost = normalised_residuals(data, fit.prediction, sigma, SampleSet::fit_held_out).squaredNorm();
  fit.bic = bic_of(data, fit.prediction, sigma, P);

  return fit;
}


void add_uncertainty(EffectSetFit& fit, const Evaluator& evaluator, const BenchData& data, const std::vector<double>& sigma) {
  const std::vector<FittedParameter> params = parameters_of(fit);
  const std::size_t P = params.size();
  fit.sd.assign(P, std::numeric_limits<double>::quiet_NaN());
  if (!fit.ok) return;
  // One more Jacobian at the fit, in plain 1/sigma weighting.
  const DifferenceRuns differences =
      forward_differences(fit.values, params, [&](const std::vector<double>& x) { return entries_of(fit, x); });
  const std::vector<double>& h = differences.h;
  const std::vector<ModelPrediction> columns = evaluator.run_all(differences.lists, RunScope::fit_training);
  const Eigen::VectorXd s = sqrt_counts(data, sigma, SampleSet::fit_training);
  const Eigen::VectorXd r0 = normalised_residuals(data, fit.prediction, sigma, SampleSet::fit_training);
  const Eigen::VectorXd r = r0.cwiseProduct(s);
  Eigen::MatrixXd J(r.size(), static_cast<Eigen::Index>(P));
  for (std::size_t j = 0; j < P; ++j) {
    if (!columns[j].ok) return;
    J.col(static_cast<Eigen::Index>(j)) =
        (normalised_residuals(data, columns[j], sigma, SampleSet::fit_training) - r0).cwiseProduct(s) / h[j];
  }
  const double n = static_cast<double>(r.size());
  double rho = 0.0;
  if (r.size() > 2) rho = r.head(r.size() - 1).dot(r.tail(r.size() - 1)) / std::max(r.squaredNorm(), 1e-300);
  rho = std::clamp(rho, 0.0, 0.99);
  const double s2 = r.squaredNorm() / std::max(1.0, n - static_cast<double>(P)) * (1.0 + rho) / (1.0 - rho);
  const Eigen::MatrixXd cov = (J.transpose() * J).completeOrthogonalDecomposition().pseudoInverse() * s2;
  for (std::size_t j = 0; j < P; ++j)
    fit.sd[j] = std::sqrt(std::max(0.0, cov(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j))));
}

std::vector<PairEstimate> rank_pairs_linear(const std::vector<EffectSetFit>& screened, const ModelPrediction& baseline,
                                            const BenchData& data, const std::vector<double>& sigma) {
  const Eigen::VectorXd r0 = normalised_residuals(data, baseline, sigma, SampleSet::fit_training);
  std::vector<PairEstimate> out;
  for (std::size_t a = 0; a < screened.size(); ++a)
    for (std::size_t b = a + 1; b < screened.size(); ++b) {
      const EffectSetFit& fa = screened[a];
      const EffectSetFit& fb = screened[b];
      if (fa.neutral_jacobian.cols() == 0 || fb.neutral_jacobian.cols() == 0) continue;
      Eigen::MatrixXd J(r0.size(), fa.neutral_jacobian.cols() + fb.neutral_jacobian.cols());
      J << fa.neutral_jacobian, fb.neutral_jacobian;
      Eigen::MatrixXd A = J.transpose() * J;
      for (Eigen::Index k = 0; k < A.rows(); ++k) A(k, k) += 1e-9 + 1e-6 * A(k, k);
      const Eigen::VectorXd delta = A.ldlt().solve(-J.transpose() * r0);
      PairEstimate e;
      e.first = a;
      e.second = b;
      e.linear_training_cost = (r0 + J * delta).squaredNorm();
      for (Eigen::Index k = 0; k < delta.size(); ++k) e.step.push_back(delta[k]);
      out.push_back(e);
    }
  std::sort(out.begin(), out.end(),
            [](const PairEstimate& x, const PairEstimate& y) { return x.linear_training_cost < y.linear_training_cost; });
  return out;
}

double best_partner_gain(const EffectSetFit& single, const std::vector<EffectSetFit>& screened, const BenchData& data,
                         const std::vector<double>& sigma, double noise_floor_cost) {
  if (!single.ok) return 0.0;
  const Eigen::VectorXd r = normalised_residuals(data, single.prediction, sigma, SampleSet::fit_training);
  const double cost = r.squaredNorm();
  const double excess = cost - noise_floor_cost;
  if (!(excess > 0.0)) return 0.0;
  double best = 0.0;
  for (const EffectSetFit& other : screened) {
    if (other.candidates == single.candidates || other.neutral_jacobian.rows() != r.size()) continue;
    const Eigen::MatrixXd& J = other.neutral_jacobian;
    Eigen::MatrixXd A = J.transpose() * J;
    for (Eigen::Index k = 0; k < A.rows(); ++k) A(k, k) += 1e-9 + 1e-6 * A(k, k);
    const Eigen::VectorXd delta = A.ldlt().solve(-J.transpose() * r);
    best = std::max(best, (cost - (r + J * delta).squaredNorm()) / excess);
  }
  return best;
}

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

}  // namespace

namespace {

SigmoidFit fit_sigmoid_direction(const Evaluator& evaluator, const BenchData& data, const ModelPrediction& baseline,
                                 const std::vector<double>& sigma, const nlohmann::json& held, const Eigen::VectorXd& r0) {
  (void)baseline;
  const Candidate* sigmoid = nullptr;
  for (const Candidate& c : candidate_library())
    if (c.name == "sigmoid_mobility") sigmoid = &c;
  SigmoidFit out;
  if (sigmoid == nullptr) return out;
  const double step = sigmoid->parameters[0].step;
  std::vector<nlohmann::json> lists;
  for (int axis = 0; axis < 3; ++axis)
    for (int part = 0; part < 2; ++part) {
      nlohmann::json h = held;
      // Unit direction along the axis as polar / azimuth angles.
      const double polar = axis == 2 ? 0.0 : M_PI / 2.0;
      const double azimuth = axis == 1 ? M_PI / 2.0 : 0.0;
      lists.push_back(nlohmann::json::array({sigmoid->entry(
          part == 0 ? std::vector<double>{step, 0.0, polar, azimuth} : std::vector<double>{0.0, step, polar, azimuth}, held)}));
    }
  const std::vector<ModelPrediction> runs = evaluator.run_all(lists, RunScope::fit_training);
  Eigen::MatrixXd J(r0.size(), 6);
  for (int k = 0; k < 6; ++k) {
    if (!runs[static_cast<std::size_t>(k)].ok) return out;
    // Column order: (u_x, v_x, u_y, v_y, u_z, v_z).
    J.col(k) = (normalised_residuals(data, runs[static_cast<std::size_t>(k)], sigma, SampleSet::fit_training) - r0) / step;
  }
  Eigen::MatrixXd A = J.transpose() * J;
  for (Eigen::Index k = 0; k < 6; ++k) A(k, k) += 1e-9 + 1e-6 * A(k, k);
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

}  // namespace

std::vector<EffectSetFit> screen_candidates(const Evaluator& evaluator, const BenchData& data,
                                            const ModelPrediction& baseline, const std::vector<double>& sigma) {
  const std::vector<Candidate>& library = candidate_library();
  const Eigen::VectorXd r0 = normalised_residuals(data, baseline, sigma, SampleSet::fit_training);
  std::vector<EffectSetFit> fits(library.size());
  std::vector<nlohmann::json> lists;
  std::vector<std::pair<std::size_t, std::size_t>> column_of;  // (candidate, parameter)
  std::vector<double> steps;
  for (std::size_t c = 0; c < library.size(); ++c) {
    fits[c].candidates = {c};
    fits[c].held = {library[c].held(data, baseline)};
    std::vector<double> x;
    for (const FittedParameter& p : library[c].parameters) x.push_back(p.neutral);
    fits[c].values = x;
    if (library[c].name == "sigmoid_mobility") continue;  // its own runs (fit_sigmoid_direction)
    for (std::size_t j = 0; j < x.size(); ++j) {
      std::vector<double> xj = x;
      const FittedParameter& p = library[c].parameters[j];
      const double h = p.neutral + p.step <= p.hi ? p.step : -p.step;
      xj[j] += h;
      lists.push_back(nlohmann::json::array({library[c].entry(xj, fits[c].held[0])}));
      column_of.emplace_back(c, j);
      steps.push_back(h);
    }
  }
  const std::vector<ModelPrediction> columns = evaluator.run_all(lists, RunScope::fit_training);
  std::vector<nlohmann::json> trial_lists;
  std::vector<std::size_t> trial_of;
  for (std::size_t c = 0; c < library.size(); ++c) {
    const std::size_t P = library[c].parameters.size();
    Eigen::MatrixXd J(r0.size(), static_cast<Eigen::Index>(P));
    bool ok = true;
    for (std::size_t k = 0; k < columns.size(); ++k) {
      if (column_of[k].first != c) continue;
      if (!columns[k].ok) {
        ok = false;
        fits[c].failure = "the run for the Jacobian failed: " + columns[k].failure;
        break;
      }
      J.col(static_cast<Eigen::Index>(column_of[k].second)) =
          (normalised_residuals(data, columns[k], sigma, SampleSet::fit_training) - r0) / steps[k];
    }
    if (!ok) continue;
    if (library[c].name == "sigmoid_mobility") {
      const SigmoidFit sf = fit_sigmoid_direction(evaluator, data, baseline, sigma, fits[c].held[0], r0);
      if (sf.ok) {
        fits[c].neutral_jacobian = sf.jacobian_along_direction;
        fits[c].values = {sf.a, sf.b, std::acos(std::clamp(sf.direction.z(), -1.0, 1.0)),
                          std::atan2(sf.direction.y(), sf.direction.x())};
        trial_lists.push_back(nlohmann::json::array({library[c].entry(fits[c].values, fits[c].held[0])}));
        trial_of.push_back(c);
        continue;
      }
    }
    fits[c].neutral_jacobian = J;
    Eigen::MatrixXd A = J.transpose() * J;
    for (Eigen::Index k = 0; k < A.rows(); ++k) A(k, k) += 1e-9 + 1e-6 * A(k, k);
    const Eigen::VectorXd delta = A.ldlt().solve(-J.transpose() * r0);
    for (std::size_t j = 0; j < P; ++j)
      fits[c].values[j] = std::clamp(fits[c].values[j] + delta[static_cast<Eigen::Index>(j)], library[c].parameters[j].lo,
                                     library[c].parameters[j].hi);
    trial_lists.push_back(nlohmann::json::array({library[c].entry(fits[c].values, fits[c].held[0])}));
    trial_of.push_back(c);
  }
  const std::vector<ModelPrediction> trials = evaluator.run_all(trial_lists, RunScope::fit_all);
  for (std::size_t k = 0; k < trials.size(); ++k) {
    EffectSetFit& f = fits[trial_of[k]];
    f.iterations = 1;
    f.effects = trial_lists[k];
    f.prediction = trials[k];
    f.ok = trials[k].ok;
    if (!f.ok) {
      f.failure = trials[k].failure;
      continue;
    }
    f.training_cost = normalised_residuals(data, f.prediction, sigma, SampleSet::fit_training).squaredNorm();
    f.held_out_cost = normalised_residuals(data, f.prediction, sigma, SampleSet::fit_held_out).squaredNorm();
    f.bic = bic_of(data, f.prediction, sigma, f.values.size());
  }
  return fits;
}

}  // namespace scopekin::discrepancy
