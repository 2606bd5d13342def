#pragma once
// The library of candidate effects the workflow tries (model/effects/EFFECTS.md): for each,
// which parameters are fitted (with units, bounds, the neutral value where the effect vanishes
// and the step of the finite-difference Jacobian), which are held, and how fitted values become
// the effect's entry in truth_effects.
//
// Held parameters (stated, host_sim/discrepancy/README.md): viscoadhesive_friction's cap
// max_friction_increase (0.25), mesenteric_retraction's exponent (1), ei_profile's bending
// section (none). sigmoid_mobility is linear in A cos(phi) and A sin(phi) for a given frequency
// and direction; those two are fitted, and the frequency is read off the residual first (its
// periodic component, 0.05-2 Hz: strongest_periodic_residual) and then, on a recording fitted on
// full runs, chosen by the model's response (sigmoid_frequency.hpp). The direction d (polar angle from
// +z, azimuth from +x) is fitted too; its first value comes from the screening: the load
// u sin(w t) + v cos(w t) is linear in the vectors u, v (six runs along the axes), and
// u = A cos(phi) d, v = A sin(phi) d is its best rank-one approximation (SVD).
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "host_sim/discrepancy/measured_recording.hpp"
#include "host_sim/discrepancy/model_run.hpp"

namespace scopekin::discrepancy {

struct FittedParameter {
    std::string key;  ///< the name in the fit (the effect's key, or a derived one)
    std::string unit;
    double lo = 0, hi = 0;
    double neutral = 0;  ///< where the effect vanishes (the fit starts there)
    double step = 0;     ///< finite-difference step
    /// The screening's coarse grid over the range (besides `neutral`): geometric, as the effects
    /// act by scale. Empty: screened by other means (sigmoid_mobility, linear in its amplitudes).
    std::vector<double> screen;
};

struct Candidate {
    std::string name;  ///< the effect's identifier
    std::string acts;  ///< where it acts, for the report
    std::vector<FittedParameter> parameters;
    /// Held parameters, read off the baseline residual where needed (sigmoid_mobility).
    std::function<nlohmann::json(const MeasuredRecording&, const ModelPrediction& baseline)> held;
    /// The truth_effects entry for fitted values and the held parameters.
    std::function<nlohmann::json(const std::vector<double>& values, const nlohmann::json& held)>
        entry;
};

/// The six effects of the host simulator's library, in EFFECTS.md order.
const std::vector<Candidate>& candidate_library();

/// Whether candidate `c`'s parameter values `a` and `b` lie within its finite-difference step of
/// each other, parameter by parameter (a fit started at one lands where one started at the other
/// would). False when either has the wrong number of values.
bool within_a_step(std::size_t c, const std::vector<double>& a, const std::vector<double>& b);

/// Nested effects: whether candidate `c` at fitted `values` is close to candidate `simpler`
/// (ei_profile with its tip and handle factors equal within their finite-difference step, 0.1).
bool reduces_to(std::size_t c, const std::vector<double>& values, std::size_t simpler);

/// And candidate `c`'s values that make it candidate `simpler` at `simpler_values`
/// (ei_scale f is ei_profile (f, f)), or empty when `c` does not contain `simpler`. A start for `c`
/// from which its fit can only explain more than `simpler` does.
std::vector<double> nested_start(std::size_t c, std::size_t simpler,
                                 const std::vector<double>& simpler_values);

/// The other way round: starts for candidate `simpler` near candidate `c` at `values` (ei_profile
/// (tip, handle) gives ei_scale at the tip's factor and at the mean of the two), or none when `c`
/// does not contain `simpler`.
std::vector<std::vector<double>> nested_projections(std::size_t c, std::size_t simpler,
                                                    const std::vector<double>& values);

/// Sigmoid mobility's frequency is searched in [kPeriodicLow_Hz, kPeriodicHigh_Hz] [Hz].
inline constexpr double kPeriodicLow_Hz = 0.05;
inline constexpr double kPeriodicHigh_Hz = 2.0;
/// Independent frequency cells (1/span wide) a line's neighbourhood must hold for its median to
/// be a continuum: 16 from a 100 s recording on (a 22-60 s one has 6-10).
inline constexpr double kMinContinuumCells = 16.0;

/// The periodic component of the baseline's residuals (every assessed output, in units of its
/// noise) that a sigmoid motion would leave: frequency [Hz] in 0.05-2 Hz, and the principal
/// direction of the position residuals at it (unit, colon frame; a first guess: the screening
/// fits the direction). On a recording long enough that the periodogram has a continuum
/// (kMinContinuumCells), the most prominent line over its neighbourhood's median power: a
/// procedure's own misfit is a low-frequency continuum (its cycles' harmonics) that can hold more
/// power than a motility line (host_sim/discrepancy/README.md, the 10-minute bench); on a short
/// one, where a neighbourhood is a few correlated cells, the strongest power.
struct PeriodicResidual {
    double frequency_Hz = 0.25;
    Eigen::Vector3d direction = Eigen::Vector3d::UnitY();
};
PeriodicResidual strongest_periodic_residual(const MeasuredRecording& data,
                                             const ModelPrediction& baseline,
                                             const std::vector<double>& sigma);

}  // namespace scopekin::discrepancy
