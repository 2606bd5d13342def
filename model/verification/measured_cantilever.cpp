#include "model/verification/measured_cantilever.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "model/beam/scope_beam.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/solvers/static_solver.hpp"

namespace scopekin::model::measured_cantilever {

namespace {

/// The last converged solution, reused as the starting point of the next solve of the fit
/// (neighbouring parameters give neighbouring shapes): ~5 Newton iterations instead of ~90.
struct WarmStart {
    bool valid = false;
    int elements = 0;
    double clamp_pitch_rad = 0;
    ScopeBeam::Configuration configuration;
};
thread_local WarmStart warm_start;

Eigen::Matrix3d pitch_rotation(double pitch_rad) {
    return Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

}  // namespace

Result simulate(double ei, double weight, double clamp_pitch_deg, int elements) {
    return simulate_profile(ei, ei, weight, clamp_pitch_deg, elements);
}

Result simulate_profile(double ei_clamp, double ei_tip, double weight, double clamp_pitch_deg,
                        int elements) {
    const double pitch_rad = clamp_pitch_deg * M_PI / 180.0;
    const Eigen::Vector3d direction(std::cos(pitch_rad), std::sin(pitch_rad), 0.0);
    std::vector<Eigen::Vector3d> nodes;
    std::vector<BeamSection> sections;
    for (int i = 0; i <= elements; ++i)
        nodes.push_back(direction * (kFreeLength_mm * i / elements));
    for (int i = 0; i < elements; ++i) {
        // Linear in the distance from the clamp, at the element's midpoint.
        const double s = (static_cast<double>(i) + 0.5) / static_cast<double>(elements);
        sections.push_back(cf_q160l::section((1.0 - s) * ei_clamp + s * ei_tip, weight));
    }
    ScopeBeam beam(std::move(nodes), std::move(sections));
    BeamLoads loads;
    loads.gravity_mm_per_s2 = Eigen::Vector3d(0.0, -kGravity_mm_per_s2, 0.0);
    NodeSupport clamp;  // the clamp holds node 0 at the origin in its reference orientation
    clamp.node = 0;
    clamp.target_position_mm = Eigen::Vector3d::Zero();
    clamp.target_rotation = Eigen::Matrix3d::Identity();
    StaticReport report;
    if (warm_start.valid && warm_start.elements == elements) {
        // Node rotations are relative to the reference (pitched) beam: the same absolute
        // orientation A = R1 P(p1) = R2 P(p2) gives R2 = R1 P(p1 - p2).
        ScopeBeam::Configuration start = warm_start.configuration;
        const Eigen::Matrix3d transfer = pitch_rotation(warm_start.clamp_pitch_rad - pitch_rad);
        for (Eigen::Matrix3d& r : start.rotations)
            r = r * transfer;
        beam.restore(start);
        StaticSettings one_step;
        one_step.load_steps = 1;
        report = solve_static(beam, loads, {clamp}, one_step);
    }
    if (!report.converged) {
        beam.reset_to_reference();
        StaticSettings settings;
        settings.load_steps = 20;  // w L^3 / EI ~ 170: the scope hangs almost vertically
        report = solve_static(beam, loads, {clamp}, settings);
    }
    if (report.converged) warm_start = {true, elements, pitch_rad, beam.configuration()};
    Result r;
    r.converged = report.converged;
    r.newton_iterations = report.total_iterations;
    const int stride = elements / 16;  // nodes per 50 mm
    double sum = 0.0;
    for (int i = 0; i < 10; ++i) {
        const std::size_t node = static_cast<std::size_t>(i * stride);
        const Eigen::Vector3d p = beam.position(node);
        const Eigen::Vector2d displacement(p.x() - kPointSpacing_mm * i, p.y());
        r.computed_mm.push_back(displacement);
        const Eigen::Vector2d measured(kMeasuredDisplacement_mm[static_cast<std::size_t>(i)][0],
                                       kMeasuredDisplacement_mm[static_cast<std::size_t>(i)][1]);
        if (i >= 1) sum += (displacement - measured).squaredNorm();
    }
    r.rms_mm = r.converged ? std::sqrt(sum / 9.0) : std::numeric_limits<double>::infinity();
    return r;
}

Fit fit_ei_over_weight(int elements) {
    // Only EI / w matters: fix w (App. B) and search EI over the measured 260-660 N cm^2 range
    // widened by 2x each way.
    const double w = cf_q160l::kWeightPerLength_N_per_mm;
    auto rms = [&](double log_ratio) {
        return simulate(std::exp(log_ratio) * w, w, 0.0, elements).rms_mm;
    };
    double a = std::log(13000.0 / w), b = std::log(132000.0 / w);
    const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
    double c = b - golden * (b - a), d = a + golden * (b - a);
    double fc = rms(c), fd = rms(d);
    Fit fit;
    fit.evaluations = 2;
    while (b - a > 1e-4) {
        if (fc < fd) {
            b = d;
            d = c;
            fd = fc;
            c = b - golden * (b - a);
            fc = rms(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + golden * (b - a);
            fd = rms(d);
        }
        ++fit.evaluations;
    }
    fit.ei_over_weight_mm3 = std::exp(0.5 * (a + b));
    fit.rms_mm = rms(0.5 * (a + b));
    return fit;
}

Fit fit_ei_over_weight_and_clamp_pitch(int elements) {
    const double w = cf_q160l::kWeightPerLength_N_per_mm;
    const Fit start = fit_ei_over_weight(elements);
    int evaluations = start.evaluations;
    // Variables: log(EI / w) and pitch in degrees; a bounded Nelder-Mead (Lagarias et al. 1998).
    auto rms = [&](const Eigen::Vector2d& v) {
        ++evaluations;
        if (std::abs(v(1)) > 15.0)
            return 1e9;  // a clamp more than 15 deg off horizontal is not "horizontal"
        return simulate(std::exp(v(0)) * w, w, v(1), elements).rms_mm;
    };
    std::array<Eigen::Vector2d, 3> simplex{
        Eigen::Vector2d(std::log(start.ei_over_weight_mm3), 0.0),
        Eigen::Vector2d(std::log(start.ei_over_weight_mm3) + 0.1, 0.0),
        Eigen::Vector2d(std::log(start.ei_over_weight_mm3), -2.0)};
    std::array<double, 3> value{start.rms_mm, rms(simplex[1]), rms(simplex[2])};
    for (int iteration = 0; iteration < 200; ++iteration) {
        // order best .. worst
        for (int i = 0; i < 2; ++i)
            for (int j = 0; j < 2 - i; ++j)
                if (value[static_cast<std::size_t>(j)] > value[static_cast<std::size_t>(j + 1)]) {
                    std::swap(value[static_cast<std::size_t>(j)],
                              value[static_cast<std::size_t>(j + 1)]);
                    std::swap(simplex[static_cast<std::size_t>(j)],
                              simplex[static_cast<std::size_t>(j + 1)]);
                }
        if (value[2] - value[0] < 1e-4 && (simplex[2] - simplex[0]).norm() < 1e-3) break;
        const Eigen::Vector2d centroid = 0.5 * (simplex[0] + simplex[1]);
        const Eigen::Vector2d reflected = centroid + (centroid - simplex[2]);
        const double fr = rms(reflected);
        if (fr < value[0]) {
            const Eigen::Vector2d expanded = centroid + 2.0 * (centroid - simplex[2]);
            const double fe = rms(expanded);
            if (fe < fr) {
                simplex[2] = expanded;
                value[2] = fe;
            } else {
                simplex[2] = reflected;
                value[2] = fr;
            }
        } else if (fr < value[1]) {
            simplex[2] = reflected;
            value[2] = fr;
        } else {
            const Eigen::Vector2d contracted = centroid + 0.5 * (simplex[2] - centroid);
            const double fc = rms(contracted);
            if (fc < value[2]) {
                simplex[2] = contracted;
                value[2] = fc;
            } else {  // shrink towards the best point
                for (std::size_t k = 1; k < 3; ++k) {
                    simplex[k] = simplex[0] + 0.5 * (simplex[k] - simplex[0]);
                    value[k] = rms(simplex[k]);
                }
            }
        }
    }
    std::size_t best = 0;
    for (std::size_t k = 1; k < 3; ++k)
        if (value[k] < value[best]) best = k;
    Fit fit;
    fit.ei_over_weight_mm3 = std::exp(simplex[best](0));
    fit.clamp_pitch_deg = simplex[best](1);
    fit.rms_mm = value[best];
    fit.evaluations = evaluations;
    return fit;
}

}  // namespace scopekin::model::measured_cantilever
