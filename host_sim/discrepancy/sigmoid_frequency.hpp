#pragma once
// sigmoid_mobility's frequency chosen by the model's own response, not by the residual's
// periodogram alone.
//
// The periodogram's strongest power is the procedure's own misfit on a deep insertion (a
// continuum at 0.05-0.1 Hz), and a 0.01 Hz cell off the truth is a third of a cycle over 36 s
// (host_sim/discrepancy/README.md, E). The screening's six runs (a unit load along each axis,
// sine and cosine at the periodogram's frequency f0) give the response's Jacobian columns
//   S_a(t) = g_a(t) sin(w0 t),   C_a(t) = g_a(t) cos(w0 t),   a = x, y, z,
// where g_a(t) is the outputs' response to a unit force per length along axis a at time t. The
// load acts on the nodes in the sigmoid at t; the scope's response to a load a fraction of a hertz
// slow is quasi-static, so g_a(t) depends on t (which nodes are in the sigmoid, the contacts) but
// not on the load's history: then g_a(t) = S_a(t) sin(w0 t) + C_a(t) cos(w0 t) exactly, and the
// columns at any other frequency f are g_a(t) sin(w t), g_a(t) cos(w t). The training cost after
// the six-parameter linear least-squares fit is predicted at every f of the band from those six
// runs, with no further run; the frequency that predicts the lowest cost is the screen's
// (a matched filter of the residual against the model's response; Kay 1993, *Fundamentals of
// Statistical Signal Processing: Estimation Theory*, Prentice Hall, sec. 13.4, least squares for
// a sinusoid's frequency). Stick-slip and a loop's handle forces make g depend on the load's
// history, so the prediction is a guide, not a verdict: on the sweep's deep insertion with a line
// at 0.35 Hz, runs at the periodogram's 0.06 Hz predicted 169 at 0.058 Hz and 172.6 at 0.3475 Hz
// (the baseline 205), where a run at 0.34 Hz itself reached 92. The screening therefore runs the
// six columns again at the scan's lowest dips and keeps whichever frequency's own runs predict
// the lowest cost.
#include <vector>

#include <Eigen/Dense>

#include "host_sim/discrepancy/analysis.hpp"
#include "host_sim/discrepancy/measured_recording.hpp"

namespace scopekin::discrepancy {

/// The time [s] of each row of normalised_residuals(data, ·, sigma, set), in its order.
std::vector<double> residual_row_times(const MeasuredRecording& data,
                                       const std::vector<double>& sigma, SampleSet set);

struct FrequencyScan {
    double frequency_Hz = 0.0;         ///< the lowest predicted cost's frequency
    double predicted_cost = 0.0;       ///< there
    double cost_at_start = 0.0;        ///< predicted at the columns' own frequency f0
    std::vector<double> profile_Hz;    ///< the scan's grid (for the report)
    std::vector<double> profile_cost;  ///< predicted cost there
    /// The profile's local minima, lowest first, each refined by a parabola through it and its
    /// grid neighbours, none within a lobe (1/span) of a lower one; the first is frequency_Hz.
    std::vector<double> dips_Hz, dips_cost;
};

/// Scans [lo_Hz, hi_Hz] for the frequencies whose six response columns best fit `r0` (rows at
/// `times_s`). `columns` are the Jacobian's six columns at `f0_Hz` in the order
/// (sin x, cos x, sin y, cos y, sin z, cos z). The grid's step is a tenth of 1/span (span: the
/// rows' time extent), at least `min_step_Hz`. An empty or mismatched input returns f0 with both
/// costs |r0|^2 and no dips.
FrequencyScan scan_sigmoid_frequency(const Eigen::MatrixXd& columns, double f0_Hz,
                                     const std::vector<double>& times_s, const Eigen::VectorXd& r0,
                                     double lo_Hz, double hi_Hz, double min_step_Hz = 0.0005);

/// The predicted training cost |r0 + J w|^2 of the least-squares w for the six columns rebuilt at
/// `f_Hz` (the quantity scan_sigmoid_frequency minimises).
double predicted_sigmoid_cost(const Eigen::MatrixXd& columns, double f0_Hz,
                              const std::vector<double>& times_s, const Eigen::VectorXd& r0,
                              double f_Hz);

}  // namespace scopekin::discrepancy
