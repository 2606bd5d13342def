#pragma once
// Small helpers shared by the model tests: seeded random vectors and rotations (every run draws
// the same numbers, so a failure reproduces) and a matrix comparison with a readable message.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <random>
#include <string>

#include "model/colon/colon_tube.hpp"
#include "model/model_error.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/world/world_effect.hpp"

namespace scopekin::model::testing {

class Random {
public:
    explicit Random(unsigned seed) : engine_(seed) {}
    double uniform(double lo, double hi) {
        return std::uniform_real_distribution<double>(lo, hi)(engine_);
    }
    Eigen::Vector3d vector(double lo, double hi) {
        return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)};
    }
    /// Uniform on the unit sphere (normalised Gaussian).
    Eigen::Vector3d unit_vector() {
        std::normal_distribution<double> n(0.0, 1.0);
        Eigen::Vector3d v;
        do {
            v = Eigen::Vector3d(n(engine_), n(engine_), n(engine_));
        } while (v.norm() < 1e-3);
        return v.normalized();
    }
    /// Rotation of angle `angle_rad` about a random axis, built with Eigen's AngleAxis (not with
    /// the model's rotation_exp, so that it can serve as an independent reference).
    Eigen::Matrix3d rotation(double angle_rad) {
        return Eigen::AngleAxisd(angle_rad, unit_vector()).toRotationMatrix();
    }

private:
    std::mt19937 engine_;
};

/// Three CF-Q160L nodes 10 mm apart (handle side first) in a straight tube along +x, inserted
/// 120 mm: node 0 at x = 100 (20 mm from the tip) 12 mm off the axis along +y, node 1 at 110,
/// 20 mm along +z, the tip at 120, 5 mm along +z. None held; `tube` is the colon at rest.
inline WorldEffectView three_node_view(const ColonTube& tube, double time_s = 0.0) {
    WorldEffectView v;
    v.time_s = time_s;
    v.time_step_s = 0.01;
    v.insertion_depth_mm = 120.0;
    v.scope_radius_mm = cf_q160l::kRadius_mm;
    v.scope_nodes_mm = {{100.0, 12.0, 0.0}, {110.0, 0.0, 20.0}, {120.0, 0.0, 5.0}};
    v.arc_from_tip_mm = {20.0, 10.0, 0.0};
    v.scope_velocities_mm_per_s.assign(3, Eigen::Vector3d::Zero());
    v.scope_axes.assign(3, Eigen::Vector3d::UnitX());
    v.scope_node_held.assign(3, false);
    v.colon_at_rest = &tube;
    return v;
}

/// Max-norm of the difference, compared against an absolute tolerance.
inline ::testing::AssertionResult matrices_near(const Eigen::MatrixXd& actual,
                                                const Eigen::MatrixXd& expected, double tolerance) {
    if (actual.rows() != expected.rows() || actual.cols() != expected.cols())
        return ::testing::AssertionFailure() << "shape " << actual.rows() << "x" << actual.cols()
                                             << " vs " << expected.rows() << "x" << expected.cols();
    const double error = (actual - expected).cwiseAbs().maxCoeff();
    if (error <= tolerance) return ::testing::AssertionSuccess();
    Eigen::IOFormat fmt(6, 0, ", ", "\n", "[", "]");
    return ::testing::AssertionFailure()
           << "max |difference| " << error << " > " << tolerance << "\nactual:\n"
           << actual.format(fmt) << "\nexpected:\n"
           << expected.format(fmt);
}

/// Runs `run` and expects a ModelError whose message contains `fragment`.
inline void expect_model_error(const std::function<void()>& run, const std::string& fragment) {
    try {
        run();
        ADD_FAILURE() << "no error; expected one mentioning '" << fragment << "'";
    } catch (const ModelError& e) {
        EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
}

}  // namespace scopekin::model::testing
