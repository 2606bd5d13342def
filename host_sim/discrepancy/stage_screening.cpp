#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "host_sim/discrepancy/ranking.hpp"
#include "host_sim/discrepancy/sigmoid_frequency.hpp"
#include "host_sim/discrepancy/sigmoid_load.hpp"
#include "host_sim/discrepancy/stages.hpp"

namespace scopekin::discrepancy {
namespace {

/// The six unit-load runs at one frequency and the two loads fitted from them: one without the
/// blocks where a unit load moved an event (row_weight), one from every block. Neither is always
/// the better: on the sweep's deep insertion with 0.008 N/mm at 0.45 Hz the event blocks misled
/// the fit (with them, the scan from 0.06 Hz found 0.272 Hz; without, 0.428 Hz), with 0.004 N/mm
/// at 0.35 Hz only they held the line (without them the scan was flat and 0.336 Hz was kept,
/// 0.43 cycle off over 36 s). Each is run, and the lower training cost kept (run_sigmoid_tries).
struct SigmoidFit {
    bool ok = false;
    SigmoidLoad without_event_blocks;
    SigmoidLoad all_blocks;
    bool all_blocks_kept = false;  ///< set when the all-blocks load ran at the lower cost
    /// The six runs' Jacobian on the uncapped training residuals (sigmoid_frequency.hpp's order).
    Eigen::MatrixXd uncapped_columns;
    /// 0 on the rows of a training block where a unit-load run changed the outputs by an event
    /// (response_event_weights), 1 elsewhere.
    Eigen::VectorXd row_weight;
    double step = 0.0;  ///< the unit loads' amplitude [N/mm]

    const SigmoidLoad& load() const {
        return all_blocks_kept && all_blocks.ok ? all_blocks : without_event_blocks;
    }
};

/// The library's sigmoid_mobility (null if the library had none).
const Candidate* sigmoid_candidate() {
    for (const Candidate& c : candidate_library())
        if (c.name == "sigmoid_mobility") return &c;
    return nullptr;
}

/// The six unit-load runs at `step` N/mm (0: the candidate's own step) and the two loads they
/// give (SigmoidFit). A block where one of the runs changed the outputs by far more than in the
/// others (a stick-and-release the load moved in time) is not proportional to the load there,
/// and a column scaled from it can dominate the fit. On the sweep's deep insertion with
/// 0.008 N/mm at 0.45 Hz, two of seven training blocks were such blocks in every column; with
/// them left out the fit at the true frequency removed 78 % of the rest of the misfit (unit loads
/// of 0.006 N/mm) where with them it removed 42 % (a replica in Python on the world's noiseless
/// outputs). With 0.004 N/mm at 0.35 Hz the fit with them was the right one.
SigmoidFit fit_sigmoid_direction(const DiscrepancyContext& context, const nlohmann::json& held,
                                 const Eigen::VectorXd& r0, double step = 0.0) {
    const Candidate* sigmoid = sigmoid_candidate();
    SigmoidFit out;
    if (sigmoid == nullptr) return out;
    if (!(step > 0.0)) step = sigmoid->parameters[0].step;
    out.step = step;
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
    const Eigen::VectorXd r0_uncapped = normalised_residuals(
        context.data, context.baseline, context.sigma, SampleSet::fit_training);
    out.uncapped_columns.resize(r0_uncapped.size(), 6);
    for (int k = 0; k < 6; ++k) {
        const ModelPrediction& run = runs[static_cast<std::size_t>(k)];
        if (!run.ok) return out;
        // Column order: (u_x, v_x, u_y, v_y, u_z, v_z).
        J.col(k) = (context.residuals(run, SampleSet::fit_training) - r0) / step;
        out.uncapped_columns.col(k) =
            (normalised_residuals(context.data, run, context.sigma, SampleSet::fit_training) -
             r0_uncapped) /
            step;
    }
    out.row_weight = response_event_weights(context.training_rows, out.uncapped_columns * step);
    if (out.row_weight.size() != r0.size()) out.row_weight = Eigen::VectorXd::Ones(r0.size());
    const double lo = sigmoid->parameters[0].lo, hi = sigmoid->parameters[0].hi;
    out.without_event_blocks = load_along_direction(J, r0, out.row_weight, lo, hi);
    out.all_blocks = load_along_direction(J, r0, Eigen::VectorXd::Ones(r0.size()), lo, hi);
    out.ok = out.without_event_blocks.ok;
    return out;
}

/// Frequencies sigmoid_mobility's six runs are made at in the screening from the scan of the
/// unit-load runs, the periodogram's included: two more cost 12 runs, and the three trial runs 3.
constexpr std::size_t kSigmoidFrequenciesTried = 3;

/// The larger unit loads' size over the candidate's step (0.002 N/mm: 0.006 N/mm, the middle of
/// the amplitudes the sweep hides): the scope's response to a load is not proportional to it
/// where friction holds the scope below a threshold, so a fit from small loads underestimates a
/// large amplitude. On the sweep's deep insertion the handle force's change for 0.001, 0.002,
/// 0.004 and 0.008 N/mm at 0.45 Hz was 0.17, 0.32, 0.66, 1.25 N at 12-15 s, but 5.3, 5.6, 6.1,
/// 7.4 N where an event moved (9-12 s) and 0.9, 2.5, 1.6, 10.7 N at 33-36 s; the fit from loads of
/// 0.002 N/mm at 0.45 Hz removed 31 % of the misfit outside the event blocks, from 0.006 N/mm 78 %.
constexpr double kLargerUnitLoadOverStep = 3.0;

/// sigmoid_mobility's four values from a load: (A cos phi, A sin phi, polar, azimuth).
std::vector<double> sigmoid_values(const SigmoidLoad& load) {
    return {load.a, load.b, std::acos(std::clamp(load.direction.z(), -1.0, 1.0)),
            std::atan2(load.direction.y(), load.direction.x())};
}

/// The frequencies tried for sigmoid_mobility, each with its direction fit and training cost.
struct SigmoidTries {
    std::vector<double> frequency_Hz;
    std::vector<const char*> from;
    std::vector<nlohmann::json> helds;
    std::vector<SigmoidFit> fits;
    std::vector<double> training_cost;
    std::size_t run = 0;  ///< tries before this index have had their trial run

    void add(double f, const char* origin, const nlohmann::json& held, SigmoidFit fit) {
        frequency_Hz.push_back(f);
        from.push_back(origin);
        helds.push_back(held);
        helds.back()["frequency_Hz"] = f;
        fits.push_back(std::move(fit));
        training_cost.push_back(std::numeric_limits<double>::infinity());
    }
    /// add() with the six unit-load runs of `step` N/mm made at `f` (fit_sigmoid_direction).
    void add_fitted(const DiscrepancyContext& context, double f, const char* origin,
                    const nlohmann::json& held, const Eigen::VectorXd& r0, double step = 0.0) {
        add(f, origin, held, SigmoidFit{});
        fits.back() = fit_sigmoid_direction(context, helds.back(), r0, step);
    }
    bool near_a_tried(double f, double tolerance_Hz) const {
        return std::any_of(frequency_Hz.begin(), frequency_Hz.end(),
                           [&](double t) { return std::abs(t - f) <= tolerance_Hz; });
    }
    std::size_t best() const {
        return static_cast<std::size_t>(
            std::min_element(training_cost.begin(), training_cost.end()) - training_cost.begin());
    }
};

/// Each try not yet run: both its loads run on the training data, the lower capped training
/// cost kept (SigmoidFit::all_blocks_kept says which).
void run_sigmoid_tries(const DiscrepancyContext& context, SigmoidTries& tries) {
    const Candidate* sigmoid = sigmoid_candidate();
    std::vector<nlohmann::json> lists;
    std::vector<std::pair<std::size_t, bool>> of;  // (try, all blocks)
    for (std::size_t k = tries.run; k < tries.fits.size(); ++k) {
        const SigmoidFit& fit = tries.fits[k];
        if (!fit.ok || sigmoid == nullptr) continue;
        for (const bool all_blocks : {false, true}) {
            const SigmoidLoad& load = all_blocks ? fit.all_blocks : fit.without_event_blocks;
            if (!load.ok) continue;
            lists.push_back(
                nlohmann::json::array({sigmoid->entry(sigmoid_values(load), tries.helds[k])}));
            of.emplace_back(k, all_blocks);
        }
    }
    const std::vector<ModelPrediction> runs =
        context.evaluator.run_all(lists, RunScope::fit_training);
    for (std::size_t t = 0; t < runs.size(); ++t) {
        if (!runs[t].ok) continue;
        const auto [k, all_blocks] = of[t];
        const double cost = context.residuals(runs[t], SampleSet::fit_training).squaredNorm();
        if (cost < tries.training_cost[k]) {
            tries.training_cost[k] = cost;
            tries.fits[k].all_blocks_kept = all_blocks;
        }
    }
    tries.run = tries.fits.size();
}

/// The scan (sigmoid_frequency.hpp) from a fit's six unit-load runs at `f0`: rows weighted as the
/// model as given's blocks are capped (an event block counts at its cap), and, if
/// `without_event_blocks`, without the blocks where a unit load moved an event
/// (SigmoidFit::row_weight).
FrequencyScan scan_from(const DiscrepancyContext& context, const SigmoidFit& fit, double f0,
                        const std::vector<double>& times, bool without_event_blocks) {
    const Eigen::VectorXd r0_uncapped = normalised_residuals(
        context.data, context.baseline, context.sigma, SampleSet::fit_training);
    Eigen::VectorXd weight = outlier_block_weights(context.training_rows, r0_uncapped);
    if (without_event_blocks && fit.row_weight.size() == weight.size())
        weight = weight.cwiseProduct(fit.row_weight);
    const Eigen::MatrixXd columns = weight.asDiagonal() * fit.uncapped_columns;
    return scan_sigmoid_frequency(columns, f0, times, r0_uncapped.cwiseProduct(weight),
                                  kPeriodicLow_Hz, kPeriodicHigh_Hz);
}

/// sigmoid_mobility's frequency from the model's response (sigmoid_frequency.hpp), on a recording
/// fitted on full runs: the six runs at the periodogram's frequency predict the cost at every
/// frequency of the band; at the scan's lowest dips more than a tenth of a lobe (the scan's
/// grid step: 0.1 cycle over the span) from every frequency tried, up to kSigmoidFrequenciesTried
/// in all, and at the lowest such dip of the scan without the event blocks, the six runs are made
/// too; each frequency's two loads are then run (training data), and the lowest training cost is
/// kept. Then the six runs are made again at the kept
/// frequency with larger loads (kLargerUnitLoadOverStep steps, or the kept fit's amplitude if
/// larger), and at their scan's lowest dip if it is more than a tenth of a lobe away; those fits
/// are run too, and the lower of them replaces the kept one if it lowers the training cost by
/// more than the noise floor's cost (`held` and `fit` updated). The linear
/// prediction alone is not trusted to choose: on the sweep's C with 0.006 N/mm at 0.1 Hz the runs
/// at 0.5 Hz predicted 351 against 374 at 0.11 Hz, and the run at 0.5 Hz cost 694 (the model as
/// given 486). Returns what was done, for the report.
nlohmann::ordered_json choose_sigmoid_frequency(const DiscrepancyContext& context,
                                                nlohmann::json& held, const Eigen::VectorXd& r0,
                                                SigmoidFit& fit) {
    using Json = nlohmann::ordered_json;
    const double f0 = held.value("frequency_Hz", 0.0);
    const std::vector<double> times =
        residual_row_times(context.data, context.sigma, SampleSet::fit_training);
    const FrequencyScan scan = scan_from(context, fit, f0, times, false);
    const FrequencyScan scan_without_events = scan_from(context, fit, f0, times, true);
    Json profile_Hz = Json::array(), profile_cost = Json::array(), dips = Json::array();
    for (std::size_t k = 0; k < scan.profile_Hz.size(); ++k) {
        profile_Hz.push_back(scan.profile_Hz[k]);
        profile_cost.push_back(scan.profile_cost[k]);
    }
    for (std::size_t k = 0; k < scan.dips_Hz.size() && k < 5; ++k)
        dips.push_back({{"frequency_Hz", scan.dips_Hz[k]}, {"predicted_cost", scan.dips_cost[k]}});
    Json dips_without_events = Json::array();
    for (std::size_t k = 0; k < scan_without_events.dips_Hz.size() && k < 5; ++k)
        dips_without_events.push_back({{"frequency_Hz", scan_without_events.dips_Hz[k]},
                                       {"predicted_cost", scan_without_events.dips_cost[k]}});

    // The frequencies tried: the periodogram's and the scan's lowest dips apart from it.
    const auto [first, last] = std::minmax_element(times.begin(), times.end());
    const double tenth_lobe_Hz = times.empty() ? 0.0 : 0.1 / std::max(*last - *first, 1e-3);
    SigmoidTries tries;
    tries.add(f0, "periodogram", held, fit);
    for (const double f : scan.dips_Hz) {
        if (tries.fits.size() >= kSigmoidFrequenciesTried) break;
        if (tries.near_a_tried(f, tenth_lobe_Hz)) continue;
        tries.add_fitted(context, f, "scan", held, r0);
    }
    // The lowest dip of the scan without the event blocks, if it is not tried already: on the
    // sweep's deep insertion with 0.008 N/mm at 0.45 Hz the scan with them found 0.272 Hz, without
    // them 0.428 Hz; with 0.004 N/mm at 0.35 Hz the scan without them was flat and only the one
    // with them found 0.348 Hz.
    for (const double f : scan_without_events.dips_Hz) {
        if (tries.near_a_tried(f, tenth_lobe_Hz)) continue;
        tries.add_fitted(context, f, "scan without the event blocks", held, r0);
        break;
    }
    run_sigmoid_tries(context, tries);

    // Larger unit loads at the kept frequency: three steps, or the fitted amplitude if larger.
    const std::size_t kept = tries.best();
    const std::size_t larger_from = tries.fits.size();
    const bool kept_ran = tries.fits[kept].ok && std::isfinite(tries.training_cost[kept]);
    const double load = std::max(kLargerUnitLoadOverStep * tries.fits[kept].step,
                                 std::hypot(tries.fits[kept].load().a, tries.fits[kept].load().b));
    if (kept_ran) {
        const double f = tries.frequency_Hz[kept];
        SigmoidFit larger = fit_sigmoid_direction(context, tries.helds[kept], r0, load);
        if (larger.ok) {
            const FrequencyScan again = scan_from(context, larger, f, times, true);
            tries.add(f, "larger loads", tries.helds[kept], std::move(larger));
            if (!again.dips_Hz.empty() && std::abs(again.dips_Hz[0] - f) > tenth_lobe_Hz) {
                tries.add_fitted(context, again.dips_Hz[0], "larger loads' scan", tries.helds[kept],
                                 r0, load);
            }
            run_sigmoid_tries(context, tries);
        }
    }
    // The larger loads' fit replaces the kept one only if it gains more than noise alone gives
    // (the noise floor's cost): on the sweep's B with 0.004 N/mm at 0.35 Hz it cost 12.1 against
    // 12.2 and its refinement ended in another valley (0.00497 N/mm, training cost 8.4, against
    // 0.00400 and 4.7 from the kept start).
    std::size_t best = tries.best();
    if (best >= larger_from &&
        !(tries.training_cost[best] < tries.training_cost[kept] - context.noise_floor))
        best = kept;
    Json tried = Json::array();
    auto number = [](double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); };
    for (std::size_t k = 0; k < tries.fits.size(); ++k) {
        const SigmoidFit& t = tries.fits[k];
        tried.push_back({{"frequency_Hz", tries.frequency_Hz[k]},
                         {"from", tries.from[k]},
                         {"unit_load_N_per_mm", t.ok ? Json(t.step) : Json(nullptr)},
                         {"fit", t.all_blocks_kept ? "all blocks" : "without the event blocks"},
                         {"runs_predict", t.ok ? number(t.load().predicted_cost) : nullptr},
                         {"training_cost", number(tries.training_cost[k])}});
    }
    if (best != 0) {
        held = tries.helds[best];
        fit = std::move(tries.fits[best]);
    }
    return {{"rule",
             "the six unit-load runs at the periodogram's frequency predict the training cost "
             "along the band (scan); the six runs are made again at its lowest dips more than a "
             "tenth of a lobe from every frequency tried, and at the lowest such dip of the scan "
             "without the blocks where a unit load moved an event; each frequency's two fits "
             "(with and without those blocks) are run on the training data; the six "
             "runs are made again at the best one with three times the unit load (or the fitted "
             "amplitude if larger), and at their scan's lowest dip, kept if they lower the "
             "training cost by more than the noise floor's cost; the lowest training cost is "
             "kept"},
            {"periodogram_Hz", f0},
            {"scan_dips", dips},
            {"scan_without_event_blocks_dips", dips_without_events},
            {"tried", tried},
            {"kept_Hz", tries.frequency_Hz[best]},
            {"scan", {{"frequency_Hz", profile_Hz}, {"predicted_cost", profile_cost}}}};
}

/// The runs of the screening's shared forward-difference Jacobian: one per parameter of every
/// candidate but sigmoid_mobility (fit_sigmoid_direction), each from its neutral values.
struct NeutralColumns {
    std::vector<nlohmann::json> lists;
    std::vector<std::pair<std::size_t, std::size_t>> column_of;  // (candidate, parameter)
    std::vector<double> steps;
};

/// Which candidates the model already carries (its truth_effects name them): a model written
/// by the workflow (model.json) given again with --model. They are not screened: a run may hold
/// an effect once (model/effects/effect_library.cpp), and the model's value is the one it has.
std::vector<bool> carried_by_model(const DiscrepancyContext& context) {
    const std::vector<Candidate>& library = candidate_library();
    std::vector<bool> carried(library.size(), false);
    for (const nlohmann::json& e : context.model.truth_effects)
        for (std::size_t c = 0; c < library.size(); ++c)
            if (e.is_object() && e.value("name", "") == library[c].name) carried[c] = true;
    return carried;
}

constexpr const char* kCarried = "already in the model (its truth_effects): not screened again";

/// Starts every candidate's fit at its neutral values; returns the Jacobian's runs (none for a
/// candidate the model carries).
NeutralColumns neutral_columns(const DiscrepancyContext& context, const std::vector<bool>& carried,
                               std::vector<EffectSetFit>& fits) {
    const std::vector<Candidate>& library = candidate_library();
    NeutralColumns n;
    for (std::size_t c = 0; c < library.size(); ++c) {
        fits[c].candidates = {c};
        fits[c].held = {library[c].held(context.data, context.baseline)};
        std::vector<double> x;
        for (const FittedParameter& p : library[c].parameters)
            x.push_back(p.neutral);
        fits[c].values = x;
        if (carried[c]) {
            fits[c].failure = kCarried;
            continue;
        }
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
    nlohmann::ordered_json sigmoid_frequency;  ///< choose_sigmoid_frequency's account, if run
};

Trials gauss_newton_steps(const DiscrepancyContext& context, const NeutralColumns& n,
                          const std::vector<ModelPrediction>& columns, const Eigen::VectorXd& r0,
                          const std::vector<bool>& carried, std::vector<EffectSetFit>& fits) {
    const std::vector<Candidate>& library = candidate_library();
    Trials trials;
    for (std::size_t c = 0; c < library.size(); ++c) {
        if (carried[c]) continue;
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
            SigmoidFit sf = fit_sigmoid_direction(context, fits[c].held[0], r0);
            if (sf.ok && !context.evaluator.windowed())
                trials.sigmoid_frequency =
                    choose_sigmoid_frequency(context, fits[c].held[0], r0, sf);
            if (sf.ok) {
                fits[c].neutral_jacobian = sf.load().jacobian_along_direction;
                fits[c].values = sigmoid_values(sf.load());
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

/// Every candidate's grid (screen_grid) but its all-neutral point (the model as given), as
/// truth_effects lists for training runs, with the candidate and point each is for. A point that
/// is a nested richer candidate's grid point too (ei_scale f is ei_profile (f, f), the same model
/// run bit for bit) is run once: it is an alias of the richer's run.
struct GridRuns {
    std::vector<std::vector<std::vector<double>>> points;  // per candidate; empty: no grid
    std::vector<nlohmann::json> lists;
    std::vector<std::pair<std::size_t, std::size_t>> of;  // (candidate, point)
    struct Alias {
        std::size_t candidate = 0, point = 0;  ///< the simpler's point
        std::size_t run = 0;                   ///< index into lists
    };
    std::vector<Alias> aliases;
};

/// The run of a richer candidate's grid point that is `simpler`'s `point`, if one is listed.
std::optional<std::size_t> nested_run(const GridRuns& g, std::size_t simpler,
                                      const std::vector<double>& point) {
    for (std::size_t r = 0; r < g.points.size(); ++r) {
        const std::vector<double> as_richer = nested_start(r, simpler, point);
        if (as_richer.empty()) continue;
        for (std::size_t k = 0; k < g.of.size(); ++k)
            if (g.of[k].first == r && g.points[r][g.of[k].second] == as_richer) return k;
    }
    return std::nullopt;
}

GridRuns grid_runs(const std::vector<EffectSetFit>& fits, const std::vector<bool>& carried,
                   bool coarse) {
    const std::vector<Candidate>& library = candidate_library();
    GridRuns g;
    g.points.resize(library.size());
    for (std::size_t c = 0; c < library.size(); ++c)
        if (!carried[c]) g.points[c] = screen_grid(library[c].parameters, coarse);
    auto add_run = [&](std::size_t c, std::size_t k) {
        g.lists.push_back(
            nlohmann::json::array({library[c].entry(g.points[c][k], fits[c].held[0])}));
        g.of.emplace_back(c, k);
    };
    std::vector<std::pair<std::size_t, std::size_t>> simpler_points;
    for (std::size_t c = 0; c < library.size(); ++c) {
        const bool nested_in_another = [&] {
            for (std::size_t r = 0; r < library.size(); ++r)
                if (!carried[r] && !g.points[c].empty() &&
                    !nested_start(r, c, g.points[c][0]).empty())
                    return true;
            return false;
        }();
        for (std::size_t k = 1; k < g.points[c].size(); ++k) {
            if (nested_in_another)
                simpler_points.emplace_back(c, k);
            else
                add_run(c, k);
        }
    }
    for (const auto& [c, k] : simpler_points) {
        if (const std::optional<std::size_t> run = nested_run(g, c, g.points[c][k]))
            g.aliases.push_back({c, k, *run});
        else
            add_run(c, k);
    }
    return g;
}

/// A candidate's screening in report.json: the Gauss-Newton step, the grid and its profiles,
/// and the start handed on.
nlohmann::ordered_json screening_json(const Candidate& c, const std::vector<double>& step,
                                      double step_cost, const GridScreen& grid, bool from_grid,
                                      const std::vector<double>& start) {
    using Json = nlohmann::ordered_json;
    auto cost = [](double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); };
    Json keys = Json::array();
    for (const FittedParameter& p : c.parameters)
        keys.push_back(p.key);
    Json out = {{"effect", c.name},
                {"parameters", keys},
                {"gauss_newton_step", {{"values", step}, {"training_cost", cost(step_cost)}}}};
    if (grid.points.empty()) {
        out["grid"] = nullptr;
    } else {
        Json points = Json::array();
        for (std::size_t k = 0; k < grid.points.size(); ++k)
            points.push_back({{"values", grid.points[k]}, {"training_cost", cost(grid.costs[k])}});
        Json profiles = Json::array();
        for (std::size_t j = 0; j < grid.profile.size(); ++j) {
            Json values = Json::array(), costs = Json::array();
            for (const auto& [v, c_v] : grid.profile[j]) {
                values.push_back(v);
                costs.push_back(cost(c_v));
            }
            profiles.push_back({{"parameter", c.parameters[j].key},
                                {"values", values},
                                {"lowest_training_cost", costs}});
        }
        out["grid"] = {{"points", points}, {"profile", profiles}};
    }
    out["start"] = from_grid ? "grid" : "gauss_newton_step";
    out["start_values"] = start;
    return out;
}

}  // namespace

Screening screen_candidates(const DiscrepancyContext& context) {
    using Json = nlohmann::ordered_json;
    const std::vector<Candidate>& library = candidate_library();
    const Eigen::VectorXd r0 = context.residuals(context.baseline, SampleSet::fit_training);
    Screening out;
    std::vector<EffectSetFit>& fits = out.fits;
    fits.resize(library.size());
    const std::vector<bool> carried = carried_by_model(context);
    const NeutralColumns n = neutral_columns(context, carried, fits);
    const std::vector<ModelPrediction> columns =
        context.evaluator.run_all(n.lists, RunScope::fit_training);
    const Trials steps = gauss_newton_steps(context, n, columns, r0, carried, fits);
    const GridRuns grid = grid_runs(fits, carried, context.evaluator.windowed());
    // One batch: the steps over every window (they are scored as they are), the grid over the
    // training ones (it only picks a start); on windows over the screening blocks' only, and
    // every cost the grid is compared with is taken there too.
    const bool windowed = context.evaluator.windowed();
    std::vector<std::pair<nlohmann::json, RunScope>> requests;
    for (const nlohmann::json& l : steps.lists)
        requests.emplace_back(l, RunScope::fit_all);
    for (const nlohmann::json& l : grid.lists)
        requests.emplace_back(l, windowed ? RunScope::fit_screening : RunScope::fit_training);
    std::vector<ModelPrediction> runs = context.evaluator.run_all(requests);
    auto training_cost = [&](const ModelPrediction& p) {
        return p.ok ? context.residuals(p, SampleSet::fit_training).squaredNorm()
                    : std::numeric_limits<double>::infinity();
    };
    auto grid_cost = [&](const ModelPrediction& p) {
        if (!windowed) return training_cost(p);
        return p.ok ? context.screening_cost(p) : std::numeric_limits<double>::infinity();
    };

    // Each candidate's start: its Gauss-Newton step, or the grid's best point when that costs less.
    std::vector<std::optional<std::size_t>> step_run(library.size());
    for (std::size_t k = 0; k < steps.of.size(); ++k)
        step_run[steps.of[k]] = k;
    std::vector<std::vector<double>> grid_costs(library.size());
    std::vector<std::vector<std::size_t>> grid_run(library.size());
    for (std::size_t c = 0; c < library.size(); ++c) {
        grid_costs[c].assign(grid.points[c].size(), std::numeric_limits<double>::infinity());
        grid_run[c].assign(grid.points[c].size(), 0);
        if (!grid.points[c].empty()) grid_costs[c][0] = grid_cost(context.baseline);
    }
    for (std::size_t k = 0; k < grid.of.size(); ++k) {
        const auto [c, point] = grid.of[k];
        const std::size_t run = steps.lists.size() + k;
        grid_costs[c][point] = grid_cost(runs[run]);
        grid_run[c][point] = run;
    }
    for (const GridRuns::Alias& a : grid.aliases) {
        const std::size_t run = steps.lists.size() + a.run;
        grid_costs[a.candidate][a.point] = grid_cost(runs[run]);
        grid_run[a.candidate][a.point] = run;
    }
    Json report = Json::array();
    std::vector<std::size_t> needs_rest;  // candidates started from a grid point, on windows
    for (std::size_t c = 0; c < library.size(); ++c) {
        EffectSetFit& f = fits[c];
        if (carried[c]) {
            f.ok = false;
            report.push_back({{"effect", library[c].name}, {"skipped", kCarried}});
            continue;
        }
        const std::vector<double> step = f.values;
        const double step_cost = step_run[c] ? training_cost(runs[*step_run[c]])
                                             : std::numeric_limits<double>::infinity();
        const double step_grid_cost =
            step_run[c] ? grid_cost(runs[*step_run[c]]) : std::numeric_limits<double>::infinity();
        const GridScreen g = summarise_grid(library[c].parameters, grid.points[c], grid_costs[c]);
        const bool from_grid = !g.points.empty() && g.best != 0 && g.costs[g.best] < step_grid_cost;
        f.iterations = 1;
        if (g.profile.size() == 1) f.screen_profile = g.profile[0];
        if (from_grid) {
            f.values = g.points[g.best];
            f.effects = nlohmann::json::array({library[c].entry(f.values, f.held[0])});
            f.prediction = runs[grid_run[c][g.best]];  // a copy: an alias shares its run
            if (windowed) needs_rest.push_back(c);
        } else if (step_run[c]) {
            f.effects = steps.lists[*step_run[c]];
            f.prediction = std::move(runs[*step_run[c]]);
        }
        f.ok = f.prediction.ok && (from_grid || step_run[c]);
        if (f.ok)
            f.failure.clear();
        else if (f.failure.empty())
            f.failure = f.prediction.failure;
        report.push_back(screening_json(library[c], step, step_cost, g, from_grid, f.values));
        if (library[c].name == "sigmoid_mobility" && !steps.sigmoid_frequency.is_null())
            report.back()["frequency"] = steps.sigmoid_frequency;
        if (windowed)
            report.back()["gauss_newton_step"]["screening_blocks_cost"] =
                std::isfinite(step_grid_cost) ? Json(step_grid_cost) : Json(nullptr);
    }
    // The grid ran on the screening blocks' windows only: the other windows at the chosen points.
    std::vector<nlohmann::json> rest_lists;
    for (std::size_t c : needs_rest)
        rest_lists.push_back(fits[c].effects);
    const std::vector<ModelPrediction> rest =
        context.evaluator.run_all(rest_lists, RunScope::fit_after_screening);
    for (std::size_t k = 0; k < needs_rest.size(); ++k) {
        EffectSetFit& f = fits[needs_rest[k]];
        if (!rest[k].ok) {
            f.ok = false;
            f.failure = rest[k].failure;
            continue;
        }
        merge_outputs(rest[k], f.prediction);
    }
    for (std::size_t c = 0; c < library.size(); ++c) {
        EffectSetFit& f = fits[c];
        if (!f.ok) continue;
        f.training_cost = context.residuals(f.prediction, SampleSet::fit_training).squaredNorm();
        f.held_out_cost = context.residuals(f.prediction, SampleSet::fit_held_out).squaredNorm();
        f.bic = bic_of(context, f.prediction, f.values.size());
        // What the start explains: the refinement and the pairs decide on it.
        report[c]["held_out_cost"] = f.held_out_cost;
        report[c]["share_explained"] = share_of(context, f);
    }
    out.report = {{"rule",
                   "every candidate from the model as given: one Gauss-Newton step (a shared "
                   "forward-difference Jacobian), and a coarse grid over each parameter's range "
                   "(training data only); the lower training cost is the start refined"},
                  {"grid_costed_on",
                   windowed ? "the training windows of blocks 0, 3, 6, 9 (fitted on windows: the "
                              "grid's costs, the model as given's and each step's "
                              "screening_blocks_cost there)"
                            : "the training data"},
                  {"baseline_training_cost", r0.squaredNorm()},
                  {"candidates", report}};
    return out;
}

}  // namespace scopekin::discrepancy
