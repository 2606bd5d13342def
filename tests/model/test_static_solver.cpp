// Static Newton solver with load stepping and prescribed supports
// (model/solvers/static_solver.hpp) against closed-form equilibria.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "model/beam/beam_loads.hpp"
#include "model/beam/rotation.hpp"
#include "model/beam/scope_beam.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/solvers/static_solver.hpp"
#include "model_test_support.hpp"

namespace scopekin::model {
namespace {

using testing::matrices_near;
using testing::Random;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

/// Slender, practically inextensible and shear-rigid section (EA L^2 / EI = 1e4 at L = 100).
BeamSection stiff_section() {
    return BeamSection{.axial_stiffness_N = 1e8,
                       .bending_stiffness_y_Nmm2 = 1e6,
                       .bending_stiffness_z_Nmm2 = 1e6,
                       .torsional_stiffness_Nmm2 = 8e5,
                       .shear_stiffness_y_N = 1e8,
                       .shear_stiffness_z_N = 1e8,
                       .mass_per_length_t_per_mm = 1e-6};
}

NodeSupport clamp(std::size_t node) {
    NodeSupport s;
    s.node = node;
    return s;
}

Eigen::VectorXd internal_force(const ScopeBeam& beam) {
    ScopeBeam::Assembly a;
    beam.assemble(a, false);
    return a.internal_force;
}

TEST(StaticSolver, UnsupportedBeamReportsASingularTangent) {
    ScopeBeam beam = straight_beam(Vec3::Zero(), Vec3::UnitX(), 100.0, 10, stiff_section());
    BeamLoads loads;
    loads.nodal.push_back({10, Vec3(0, 1.0, 0), Vec3::Zero()});
    const StaticReport report = solve_static(beam, loads, {});
    EXPECT_FALSE(report.converged);
    EXPECT_NE(report.message.find("singular"), std::string::npos) << report.message;
    // Nothing converged, so the beam is left where it started.
    for (std::size_t i = 0; i < beam.node_count(); ++i)
        EXPECT_TRUE(matrices_near(beam.position(i), beam.reference_position(i), 0.0))
            << "node " << i;
}

// Prescribed stretch: node 0 clamped, the last node pulled along the axis by delta. The
// co-rotational strain is (l - l0) / l0, so the axial force is exactly N = EA delta / L for any
// delta, every node moves in proportion to its arc length, and the clamp reacts with -N e_x.
TEST(StaticSolver, PrescribedAxialDisplacementGivesForceEAdeltaOverL) {
    const double length = 100.0, delta = 2.0;
    const BeamSection s = cf_q160l::section();  // EA = 3.17 kN: a 2 % stretch
    ScopeBeam beam = straight_beam(Vec3::Zero(), Vec3::UnitX(), length, 10, s);
    NodeSupport pull = clamp(10);
    pull.target_position_mm = Vec3(length + delta, 0, 0);
    const StaticReport report = solve_static(beam, BeamLoads{}, {clamp(0), pull});
    ASSERT_TRUE(report.converged) << report.message;
    const double n = s.axial_stiffness_N * delta / length;
    const Eigen::VectorXd f = internal_force(beam);
    EXPECT_NEAR(f(0), -n, 1e-9 * n);  // reaction at the clamp
    EXPECT_NEAR(f(60), n, 1e-9 * n);  // force needed at the pulled end
    EXPECT_LT(f.segment<5>(1).cwiseAbs().maxCoeff(), 1e-9 * n);
    for (std::size_t i = 0; i < beam.node_count(); ++i) {
        const Vec3 expected = beam.reference_position(i) * (1.0 + delta / length);
        EXPECT_TRUE(matrices_near(beam.position(i), expected, 1e-9 * length)) << "node " << i;
        EXPECT_TRUE(matrices_near(beam.rotation(i), Mat3::Identity(), 1e-12)) << "node " << i;
    }
}

/// Pure bending into an arc: every element carries the same end moment M = EI theta / L, so
/// each element's chord keeps its length l (no axial or shear force) and turns by theta / n:
/// the nodes lie on the polygon inscribed in a circle of radius R = l / (2 sin(theta / 2n)),
/// node k at R (sin(k theta/n), 1 - cos(k theta/n)) with rotation k theta / n about z.
/// This is exact for the discrete model; as n -> inf, R -> L / theta (the continuous arc).
void expect_discrete_arc(const ScopeBeam& beam, double theta, double tolerance_mm) {
    const std::size_t n = beam.element_count();
    const double l = beam.arc_length_mm(n) / static_cast<double>(n);
    const double per_element = theta / static_cast<double>(n);
    const double radius = l / (2.0 * std::sin(per_element / 2.0));
    for (std::size_t k = 0; k <= n; ++k) {
        const double phi = per_element * static_cast<double>(k);
        EXPECT_TRUE(matrices_near(beam.position(k),
                                  Vec3(radius * std::sin(phi), radius * (1.0 - std::cos(phi)), 0.0),
                                  tolerance_mm))
            << "node " << k;
        EXPECT_TRUE(
            matrices_near(beam.rotation(k), Mat3(Eigen::AngleAxisd(phi, Vec3::UnitZ())), 1e-9))
            << "node " << k;
    }
}

// Prescribed 90 deg end rotation about z, end translations free.
TEST(StaticSolver, PrescribedEndRotationBendsTheBeamIntoACircularArc) {
    const double length = 300.0, theta = M_PI / 2.0;
    const BeamSection s = cf_q160l::section();
    ScopeBeam beam = straight_beam(Vec3::Zero(), Vec3::UnitX(), length, 15, s);
    NodeSupport end;
    end.node = 15;
    end.fixed_translation = {false, false, false};
    end.target_rotation = Mat3(Eigen::AngleAxisd(theta, Vec3::UnitZ()));
    const StaticReport report = solve_static(beam, BeamLoads{}, {clamp(0), end});
    ASSERT_TRUE(report.converged) << report.message << "\n" << report.convergence_table();
    expect_discrete_arc(beam, theta, 1e-7 * length);
    // Continuum: tip at (L sin(theta) / theta, L (1 - cos theta) / theta); the inscribed polygon
    // differs by a factor (theta/2n) / sin(theta/2n) - 1 ~ theta^2 / (24 n^2) = 4.6e-4.
    const Vec3 arc_tip(length * std::sin(theta) / theta, length * (1.0 - std::cos(theta)) / theta,
                       0.0);
    EXPECT_LT((beam.position(15) - arc_tip).norm(), 6e-4 * length);
    // Reactions: -EI theta / L about z at the clamp, +EI theta / L at the driven end.
    const double moment = s.bending_stiffness_z_Nmm2 * theta / length;
    const Eigen::VectorXd f = internal_force(beam);
    EXPECT_NEAR(f(5), -moment, 1e-6 * moment);
    EXPECT_NEAR(f(6 * 15 + 5), moment, 1e-6 * moment);
    EXPECT_LT(f.segment<3>(6 * 15).norm(),
              1e-5 * moment / length);  // free end translations: no force
}

// The same arc, load-controlled: a fixed end moment M = EI theta / L about z.
TEST(StaticSolver, EndMomentBendsTheBeamIntoTheSameArc) {
    const double length = 300.0, theta = M_PI / 2.0;
    const BeamSection s = cf_q160l::section();
    ScopeBeam beam = straight_beam(Vec3::Zero(), Vec3::UnitX(), length, 15, s);
    BeamLoads loads;
    loads.nodal.push_back(
        {15, Vec3::Zero(), Vec3(0, 0, s.bending_stiffness_z_Nmm2 * theta / length)});
    const StaticReport report = solve_static(beam, loads, {clamp(0)});
    ASSERT_TRUE(report.converged) << report.message << "\n" << report.convergence_table();
    expect_discrete_arc(beam, theta, 1e-7 * length);
}

// A rest curvature (a bending section angulated by its wires, ScopeBeam::set_rest_curvature):
// the free cantilever takes the arc of that curvature with no load at all and no strain energy,
// and an end moment -EI kappa undoes it (M = EI (kappa - kappa_rest), Euler-Bernoulli).
TEST(StaticSolver, ARestCurvatureBendsAFreeBeamIntoItsArcAndAnEndMomentStraightensIt) {
    const double length = 300.0, theta = M_PI / 2.0;
    const BeamSection s = cf_q160l::section();
    ScopeBeam beam = straight_beam(Vec3::Zero(), Vec3::UnitX(), length, 15, s);
    // The hand turns the wheel in ten steps; each is resolved in the elements' current frames.
    for (int turn = 1; turn <= 10; ++turn) {
        for (std::size_t e = 0; e < beam.element_count(); ++e)
            beam.set_rest_curvature(e, Vec3(0, 0, 0.1 * turn * theta / length));
        const StaticReport report = solve_static(beam, BeamLoads{}, {clamp(0)});
        ASSERT_TRUE(report.converged) << report.message << "\n" << report.convergence_table();
    }
    expect_discrete_arc(beam, theta, 1e-7 * length);
    EXPECT_LT(beam.strain_energy_Nmm(), 1e-9 * s.bending_stiffness_z_Nmm2 / length);

    BeamLoads straighten;
    straighten.nodal.push_back(
        {15, Vec3::Zero(), Vec3(0, 0, -s.bending_stiffness_z_Nmm2 * theta / length)});
    const StaticReport report = solve_static(beam, straighten, {clamp(0)});
    ASSERT_TRUE(report.converged) << report.message << "\n" << report.convergence_table();
    for (std::size_t k = 0; k < beam.node_count(); ++k)
        EXPECT_TRUE(matrices_near(beam.position(k), beam.reference_position(k), 1e-6 * length))
            << "node " << k << ": " << beam.position(k).transpose();
    // Straight again, but under the moment: its strain energy is the arc's, M^2 L / (2 EI).
    const double moment = s.bending_stiffness_z_Nmm2 * theta / length;
    EXPECT_NEAR(beam.strain_energy_Nmm(),
                moment * moment * length / (2.0 * s.bending_stiffness_z_Nmm2),
                1e-6 * moment * theta);
}

// Small tip load on a beam along an arbitrary direction, load perpendicular to it: the linear
// Timoshenko result delta = P L^3 / 3EI + P L / kGA along the load (the elements are exact for
// end loads). Nonlinear corrections are O((delta / L)^2) = 1e-8 here.
TEST(StaticSolver, SmallTipLoadOnAnObliqueBeamMatchesTimoshenkoTheory) {
    const double length = 150.0;
    BeamSection s = cf_q160l::section();
    const Vec3 direction = Vec3(1, 2, 2).normalized();
    const Vec3 load_direction = direction.cross(Vec3(0.3, -1, 0.5)).normalized();
    const double expected_per_newton =
        std::pow(length, 3) / (3 * s.bending_stiffness_z_Nmm2) + length / s.shear_stiffness_y_N;
    const double p = 1e-4 * length / expected_per_newton;  // tip deflection = 1e-4 L
    ScopeBeam beam = straight_beam(Vec3(10, -20, 30), direction, length, 12, s);
    BeamLoads loads;
    loads.nodal.push_back({12, p * load_direction, Vec3::Zero()});
    const StaticReport report = solve_static(beam, loads, {clamp(0)});
    ASSERT_TRUE(report.converged) << report.message;
    const Vec3 displacement = beam.position(12) - beam.reference_position(12);
    const double expected = p * expected_per_newton;
    EXPECT_NEAR(displacement.dot(load_direction), expected, 1e-6 * expected);
    EXPECT_LT(displacement.dot(direction.cross(load_direction)), 1e-6 * expected);
}

// Gravity lumped as rho A g l / 2 per element end (scope_beam.hpp) on a shear-rigid cantilever:
// the consistent load vector would add end moments +-w l^2 / 12 per element; they cancel at
// inner nodes, the clamp absorbs one, and the missing -w l^2 / 12 at the tip adds
// (w l^2 / 12) L^2 / 2EI. So delta = w L^4 / 8EI (1 + 1 / (3 n^2)) exactly for the linear model.
TEST(StaticSolver, SmallGravitySagMatchesTheLumpedLoadClosedForm) {
    const double length = 200.0;
    const std::size_t n = 8;
    BeamSection s = stiff_section();
    s.shear_stiffness_y_N = s.shear_stiffness_z_N = std::numeric_limits<double>::infinity();
    s.bending_stiffness_z_Nmm2 = 3e6;  // sag is in the x-z plane: EI_y must be the one used
    ScopeBeam beam = straight_beam(Vec3::Zero(), Vec3::UnitX(), length, n, s);
    // Gravity sized for a tip sag of about 1e-4 L.
    const double ei = s.bending_stiffness_y_Nmm2;
    const double g = 1e-4 * length * 8 * ei / (s.mass_per_length_t_per_mm * std::pow(length, 4));
    BeamLoads loads;
    loads.gravity_mm_per_s2 = Vec3(0, 0, -g);
    const StaticReport report = solve_static(beam, loads, {clamp(0)});
    ASSERT_TRUE(report.converged) << report.message;
    const double w = s.mass_per_length_t_per_mm * g;
    const double expected =
        w * std::pow(length, 4) / (8 * ei) * (1.0 + 1.0 / (3.0 * double(n * n)));
    EXPECT_NEAR(-beam.position(n).z(), expected, 1e-6 * expected);
    EXPECT_NEAR(beam.position(n).y(), 0.0, 1e-12);
}

TEST(StaticSolver, ReportListsLoadStepsEndingAtOne) {
    ScopeBeam beam = straight_beam(Vec3::Zero(), Vec3::UnitX(), 100.0, 10, stiff_section());
    BeamLoads loads;
    loads.nodal.push_back({10, Vec3(0, -1.0, 0), Vec3::Zero()});  // P L^2 / EI = 0.01: mild
    StaticSettings settings;
    settings.load_steps = 4;
    const StaticReport report = solve_static(beam, loads, {clamp(0)}, settings);
    ASSERT_TRUE(report.converged) << report.message;
    EXPECT_EQ(report.message, "converged");
    ASSERT_EQ(report.steps.size(), 4u);
    int iterations = 0;
    for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_DOUBLE_EQ(report.steps[i].load_factor, 0.25 * double(i + 1));
        EXPECT_TRUE(report.steps[i].converged);
        EXPECT_GE(report.steps[i].iterations, 1);
        EXPECT_LE(report.steps[i].iterations, settings.max_iterations);
        iterations += report.steps[i].iterations;
    }
    EXPECT_EQ(report.total_iterations, iterations);
    EXPECT_FALSE(report.convergence_table().empty());
}

// A hard problem in one step with few iterations allowed: rejected steps are halved, accepted
// load factors increase strictly and the last accepted one is 1.
TEST(StaticSolver, RejectedStepsAreHalvedAndTheAcceptedOnesReachOne) {
    const BeamSection s = stiff_section();
    ScopeBeam beam = straight_beam(Vec3::Zero(), Vec3::UnitX(), 100.0, 10, s);
    BeamLoads loads;
    // End moment rolling the beam into 3/4 of a circle.
    loads.nodal.push_back(
        {10, Vec3::Zero(), Vec3(0, 0, 1.5 * M_PI * s.bending_stiffness_z_Nmm2 / 100.0)});
    StaticSettings settings;
    settings.load_steps = 1;
    settings.max_iterations = 6;
    const StaticReport report = solve_static(beam, loads, {clamp(0)}, settings);
    ASSERT_TRUE(report.converged) << report.message << "\n" << report.convergence_table();
    double last = 0.0;
    int rejected = 0;
    for (const LoadStepLog& step : report.steps) {
        if (!step.converged) {
            ++rejected;
            continue;
        }
        EXPECT_GT(step.load_factor, last);
        last = step.load_factor;
    }
    EXPECT_GE(rejected, 1) << report.convergence_table();
    EXPECT_DOUBLE_EQ(last, 1.0);
    EXPECT_TRUE(report.steps.back().converged);
    expect_discrete_arc(beam, 1.5 * M_PI, 1e-6 * 100.0);
}

}  // namespace
}  // namespace scopekin::model
