// Planar bending modes (model/modal/planar_modes.hpp) against the Euler-Bernoulli cantilever
// and Rayleigh's closed form for the modal damping ratio.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>

#include "model/beam/beam_loads.hpp"
#include "model/modal/planar_modes.hpp"
#include "model/scope/cf_q160l.hpp"
#include "model/solvers/static_solver.hpp"

namespace scopekin::model {
namespace {

using Vec3 = Eigen::Vector3d;

/// Euler-Bernoulli limit: no shear flexibility, no rotary inertia.
BeamSection euler_bernoulli_section() {
    BeamSection s;
    s.axial_stiffness_N = 1e8;
    s.bending_stiffness_y_Nmm2 = 1e6;
    s.bending_stiffness_z_Nmm2 = 1e6;
    s.torsional_stiffness_Nmm2 = 1e6;
    s.mass_per_length_t_per_mm = 2e-6;
    return s;  // shear stiffness +inf, rotary inertias 0 by default
}

// Clamped-free Euler-Bernoulli beam: f_n = (beta_n L)^2 / (2 pi L^2) sqrt(EI / rho A) with
// beta_n L = 1.8751041, 4.6940911, 7.8547574 (roots of cos x cosh x = -1). Cubic Hermite elements
// with consistent mass converge as (l / L)^4: with 40 elements the third mode is within ~1e-6.
TEST(PlanarModes, FineMeshMatchesTheEulerBernoulliCantilever) {
    const double length = 1000.0;
    const BeamSection s = euler_bernoulli_section();
    const ScopeBeam beam = straight_beam(Vec3::Zero(), Vec3::UnitX(), length, 40, s);
    const std::vector<PlanarMode> modes = planar_bending_modes(beam, RayleighDamping{}, 3);
    ASSERT_EQ(modes.size(), 3u);
    const std::array<double, 3> beta_l{1.8751041, 4.6940911, 7.8547574};
    for (std::size_t i = 0; i < 3; ++i) {
        const double expected = beta_l[i] * beta_l[i] / (2 * M_PI * length * length) *
                                std::sqrt(s.bending_stiffness_z_Nmm2 / s.mass_per_length_t_per_mm);
        EXPECT_NEAR(modes[i].frequency_hz / expected, 1.0, 1e-5) << "mode " << i + 1;
    }
}

// With C = a' M + b' K and K phi = w^2 M phi: zeta = phi^T C phi / (2 w phi^T M phi)
// = a' / (2 w) + b' w / 2, for every mode, whatever its shape.
TEST(PlanarModes, DampingRatioIsRayleighsClosedForm) {
    const ScopeBeam beam =
        straight_beam(Vec3::Zero(), Vec3::UnitX(), 600.0, 20, cf_q160l::section());
    const RayleighDamping damping = cf_q160l::damping();
    const std::vector<PlanarMode> modes = planar_bending_modes(beam, damping, 5);
    ASSERT_EQ(modes.size(), 5u);
    for (std::size_t i = 0; i < modes.size(); ++i) {
        const double w = 2 * M_PI * modes[i].frequency_hz;
        const double expected =
            damping.mass_coefficient_per_s / (2 * w) + damping.stiffness_coefficient_s * w / 2;
        EXPECT_NEAR(modes[i].damping_ratio, expected, 1e-9 * expected) << "mode " << i + 1;
        if (i > 0) {
            EXPECT_GT(modes[i].frequency_hz, modes[i - 1].frequency_hz);
        }
    }
}

// The header promises the modes of the reference configuration. A beam object that has been
// deformed since (here: bent by gravity, 300 mm of CF-Q160L sags ~200 mm) must give the same
// modes as a fresh one.
TEST(PlanarModes, AreThoseOfTheReferenceConfigurationWhateverThePose) {
    const ScopeBeam fresh =
        straight_beam(Vec3::Zero(), Vec3::UnitX(), 300.0, 15, cf_q160l::section());
    ScopeBeam bent = fresh;
    BeamLoads gravity;
    gravity.gravity_mm_per_s2 = Vec3(0, -kGravity_mm_per_s2, 0);
    NodeSupport clamp;
    ASSERT_TRUE(solve_static(bent, gravity, {clamp}).converged);
    ASSERT_LT(bent.position(15).y(), -100.0);
    const std::vector<PlanarMode> expected = planar_bending_modes(fresh, cf_q160l::damping(), 3);
    const std::vector<PlanarMode> actual = planar_bending_modes(bent, cf_q160l::damping(), 3);
    ASSERT_EQ(actual.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
        EXPECT_NEAR(actual[i].frequency_hz, expected[i].frequency_hz,
                    1e-9 * expected[i].frequency_hz)
            << "mode " << i + 1;
        EXPECT_NEAR(actual[i].damping_ratio, expected[i].damping_ratio, 1e-9) << "mode " << i + 1;
    }
}

// A clamped chain of n elements has 2n planar DOFs, so at most 2n modes.
TEST(PlanarModes, ReturnsAtMostTwoModesPerFreeNode) {
    const ScopeBeam beam =
        straight_beam(Vec3::Zero(), Vec3::UnitX(), 100.0, 3, euler_bernoulli_section());
    EXPECT_EQ(planar_bending_modes(beam, RayleighDamping{}, 100).size(), 6u);
    EXPECT_EQ(planar_bending_modes(beam, RayleighDamping{}, 2).size(), 2u);
}

}  // namespace
}  // namespace scopekin::model
