#include "host_sim/discrepancy/sigmoid_frequency.hpp"

#include <algorithm>
#include <cmath>

namespace scopekin::discrepancy {
namespace {

/// g_a(t_i) for the three axes (rows x 3), from the columns at f0: S sin(w0 t) + C cos(w0 t).
Eigen::MatrixXd instantaneous_response(const Eigen::MatrixXd& columns, double f0_Hz,
                                       const std::vector<double>& times_s) {
    const double w0 = 2.0 * M_PI * f0_Hz;
    Eigen::MatrixXd g(columns.rows(), 3);
    for (Eigen::Index i = 0; i < columns.rows(); ++i) {
        const double s = std::sin(w0 * times_s[static_cast<std::size_t>(i)]);
        const double c = std::cos(w0 * times_s[static_cast<std::size_t>(i)]);
        for (int a = 0; a < 3; ++a)
            g(i, a) = columns(i, 2 * a) * s + columns(i, 2 * a + 1) * c;
    }
    return g;
}

/// |r0 + J w|^2 at the least-squares w, J = [g_a sin(w t), g_a cos(w t)], with the screening's
/// ridge (1e-9 + 1e-6 of each diagonal: fit_sigmoid_direction's).
double cost_at(const Eigen::MatrixXd& g, const std::vector<double>& times_s,
               const Eigen::VectorXd& r0, double f_Hz) {
    const double w = 2.0 * M_PI * f_Hz;
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    Eigen::Matrix<double, 6, 1> row;
    for (Eigen::Index i = 0; i < g.rows(); ++i) {
        const double s = std::sin(w * times_s[static_cast<std::size_t>(i)]);
        const double c = std::cos(w * times_s[static_cast<std::size_t>(i)]);
        for (int a = 0; a < 3; ++a) {
            row[2 * a] = g(i, a) * s;
            row[2 * a + 1] = g(i, a) * c;
        }
        A.selfadjointView<Eigen::Lower>().rankUpdate(row);
        b += row * r0[i];
    }
    A = A.selfadjointView<Eigen::Lower>();
    for (int k = 0; k < 6; ++k)
        A(k, k) += 1e-9 + 1e-6 * A(k, k);
    const Eigen::Matrix<double, 6, 1> x = A.ldlt().solve(-b);
    // |r0 + J x|^2 = |r0|^2 + 2 x.b + x.A x (A without the ridge would be exact; the ridge is
    // a millionth of it).
    return std::max(0.0, r0.squaredNorm() + 2.0 * x.dot(b) + x.dot(A * x));
}

bool usable(const Eigen::MatrixXd& columns, const std::vector<double>& times_s,
            const Eigen::VectorXd& r0) {
    return columns.cols() == 6 && columns.rows() == r0.size() &&
           times_s.size() == static_cast<std::size_t>(r0.size()) && r0.size() > 6 &&
           columns.allFinite() && r0.allFinite();
}

}  // namespace

std::vector<double> residual_row_times(const MeasuredRecording& data,
                                       const std::vector<double>& sigma, SampleSet set) {
    // The row order of normalised_residuals (analysis.cpp).
    std::vector<double> t;
    for (std::size_t o = 0; o < data.outputs.size(); ++o) {
        if (!assessable(sigma, o)) continue;
        const MeasuredSeries& m = data.outputs[o];
        if (samples_in_set(data, m, set) == 0) continue;
        for (const double time : m.time_s) {
            if (!in_set(data, time, set)) continue;
            for (int c = 0; c < m.components; ++c)
                t.push_back(time);
        }
    }
    return t;
}

double predicted_sigmoid_cost(const Eigen::MatrixXd& columns, double f0_Hz,
                              const std::vector<double>& times_s, const Eigen::VectorXd& r0,
                              double f_Hz) {
    if (!usable(columns, times_s, r0)) return r0.squaredNorm();
    return cost_at(instantaneous_response(columns, f0_Hz, times_s), times_s, r0, f_Hz);
}

FrequencyScan scan_sigmoid_frequency(const Eigen::MatrixXd& columns, double f0_Hz,
                                     const std::vector<double>& times_s, const Eigen::VectorXd& r0,
                                     double lo_Hz, double hi_Hz, double min_step_Hz) {
    FrequencyScan out;
    out.frequency_Hz = f0_Hz;
    out.predicted_cost = out.cost_at_start = r0.squaredNorm();
    if (!usable(columns, times_s, r0) || !(hi_Hz > lo_Hz)) return out;
    const Eigen::MatrixXd g = instantaneous_response(columns, f0_Hz, times_s);
    out.cost_at_start = out.predicted_cost = cost_at(g, times_s, r0, f0_Hz);
    const auto [first, last] = std::minmax_element(times_s.begin(), times_s.end());
    const double span_s = std::max(*last - *first, 1e-3);
    // A tenth of a lobe: a line's cost is within a few percent of its minimum on the grid.
    const double step = std::max(0.1 / span_s, min_step_Hz);
    const int n = static_cast<int>(std::floor((hi_Hz - lo_Hz) / step + 1e-9)) + 1;
    for (int k = 0; k < n; ++k) {
        const double f = lo_Hz + step * k;
        out.profile_Hz.push_back(f);
        out.profile_cost.push_back(cost_at(g, times_s, r0, f));
    }
    // Local minima (an end counts against its one neighbour), lowest first.
    const std::vector<double>& c = out.profile_cost;
    std::vector<std::size_t> minima;
    for (std::size_t k = 0; k < c.size(); ++k)
        if ((k == 0 || c[k] < c[k - 1]) && (k + 1 == c.size() || c[k] <= c[k + 1]))
            minima.push_back(k);
    std::sort(minima.begin(), minima.end(),
              [&](std::size_t a, std::size_t b) { return c[a] < c[b]; });
    const double lobe_Hz = 1.0 / span_s;
    for (const std::size_t k : minima) {
        double f = out.profile_Hz[k], cost = c[k];
        if (k > 0 && k + 1 < c.size()) {
            // The parabola's vertex through the minimum and its neighbours (equal spacing).
            const double curvature = c[k - 1] - 2.0 * c[k] + c[k + 1];
            if (curvature > 0.0) {
                const double f_vertex = f + 0.5 * step * (c[k - 1] - c[k + 1]) / curvature;
                const double c_vertex = cost_at(g, times_s, r0, f_vertex);
                if (c_vertex < cost) {
                    f = f_vertex;
                    cost = c_vertex;
                }
            }
        }
        const bool near_a_lower = std::any_of(out.dips_Hz.begin(), out.dips_Hz.end(),
                                              [&](double d) { return std::abs(d - f) <= lobe_Hz; });
        if (near_a_lower) continue;
        out.dips_Hz.push_back(f);
        out.dips_cost.push_back(cost);
    }
    if (!out.dips_Hz.empty() && out.dips_cost[0] < out.cost_at_start) {
        out.frequency_Hz = out.dips_Hz[0];
        out.predicted_cost = out.dips_cost[0];
    }
    return out;
}

}  // namespace scopekin::discrepancy
