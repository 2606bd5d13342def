// Linear Timoshenko element (model/beam/timoshenko_element.hpp) against closed forms.
//
// Completeness argument for the stiffness: K is fixed by (i) symmetry, (ii) K r = 0 for the six
// rigid-body motions r and (iii) its node-2 block K22, because with node-2 rigid motion
// r2 = G r1 one gets K21 = -K22 G and K11 = G^T K22 G. (iii) is checked through the cantilever
// flexibility K22^-1, which for this "exact" two-node Timoshenko element equals the closed-form
// flexibility of a Timoshenko cantilever with end loads (Przemieniecki 1968, Sec. 5.6).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

#include "model/beam/timoshenko_element.hpp"
#include "model_test_support.hpp"

namespace scopekin::model {
namespace {

using testing::matrices_near;
using testing::Random;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// Deliberately different values in the two bending planes, so a swapped index shows.
BeamSection test_section() {
    return BeamSection{.axial_stiffness_N = 3000.0,
                       .bending_stiffness_y_Nmm2 = 20000.0,
                       .bending_stiffness_z_Nmm2 = 35000.0,
                       .torsional_stiffness_Nmm2 = 7000.0,
                       .shear_stiffness_y_N = 250.0,
                       .shear_stiffness_z_N = 300.0,
                       .mass_per_length_t_per_mm = 1.2e-6,
                       .rotary_inertia_y_t_mm = 1.1e-5,
                       .rotary_inertia_z_t_mm = 1.6e-5,
                       .polar_inertia_t_mm = 2.7e-5};
}
constexpr double kLength =
    12.0;  // mm: short, so shear adds a large share (phi_y = 12 EI_z/(kGA l^2) = 11.7)

/// The six rigid-body motions of an element from x = 0 to x = l (small rotations about node 1):
/// translations, a twist (theta_x = 1), theta_y = 1 (lowers w: w = -x) and theta_z = 1 (v = +x).
Eigen::Matrix<double, 12, 6> rigid_body_modes(double l) {
    Eigen::Matrix<double, 12, 6> r = Eigen::Matrix<double, 12, 6>::Zero();
    for (int c = 0; c < 3; ++c)
        r(c, c) = r(6 + c, c) = 1.0;  // translations
    r(3, 3) = r(9, 3) = 1.0;          // about x
    r(4, 4) = r(10, 4) = 1.0;         // about y ...
    r(8, 4) = -l;                     // ... moves node 2 along -z
    r(5, 5) = r(11, 5) = 1.0;         // about z ...
    r(7, 5) = l;                      // ... moves node 2 along +y
    return r;
}

/// Closed-form flexibility of a Timoshenko cantilever clamped at node 1, loaded at node 2 with
/// [Fx Fy Fz Mx My Mz]: u = F l/EA; v = Fy (l^3/3EI_z + l/kGA_y) + Mz l^2/2EI_z, theta_z = Fy l^2/2EI_z
/// + Mz l/EI_z; w = Fz (l^3/3EI_y + l/kGA_z) - My l^2/2EI_y, theta_y = -Fz l^2/2EI_y + My l/EI_y
/// (a +z deflection turns the section about -y); theta_x = Mx l/GJ. Shear adds no end rotation.
Mat6 cantilever_flexibility(const BeamSection& s, double l) {
    Mat6 f = Mat6::Zero();
    f(0, 0) = l / s.axial_stiffness_N;
    f(1, 1) = l * l * l / (3.0 * s.bending_stiffness_z_Nmm2) + l / s.shear_stiffness_y_N;
    f(1, 5) = f(5, 1) = l * l / (2.0 * s.bending_stiffness_z_Nmm2);
    f(5, 5) = l / s.bending_stiffness_z_Nmm2;
    f(2, 2) = l * l * l / (3.0 * s.bending_stiffness_y_Nmm2) + l / s.shear_stiffness_z_N;
    f(2, 4) = f(4, 2) = -l * l / (2.0 * s.bending_stiffness_y_Nmm2);
    f(4, 4) = l / s.bending_stiffness_y_Nmm2;
    f(3, 3) = l / s.torsional_stiffness_Nmm2;
    return f;
}

TEST(TimoshenkoStiffness, IsSymmetric) {
    const Mat12 k = timoshenko_local_stiffness(test_section(), kLength);
    EXPECT_TRUE(matrices_near(k, k.transpose(), 0.0));
}

TEST(TimoshenkoStiffness, AnnihilatesTheSixRigidBodyMotions) {
    const Mat12 k = timoshenko_local_stiffness(test_section(), kLength);
    const double scale = k.cwiseAbs().maxCoeff();
    EXPECT_TRUE(matrices_near(k * rigid_body_modes(kLength), Eigen::Matrix<double, 12, 6>::Zero(),
                              1e-13 * scale * kLength));
}

TEST(TimoshenkoStiffness, HasExactlySixZeroEigenvaluesAndTheRestPositive) {
    // Lengths and rotations scaled by l so that every entry has the unit N mm (eigenvalues comparable).
    Mat12 scaling = Mat12::Identity();
    for (int i : {0, 1, 2, 6, 7, 8})
        scaling(i, i) = kLength;
    const Mat12 k = scaling * timoshenko_local_stiffness(test_section(), kLength) * scaling;
    const Eigen::SelfAdjointEigenSolver<Mat12> eig(k);
    const Vec12 lambda = eig.eigenvalues();  // ascending
    const double largest = lambda(11);
    for (int i = 0; i < 6; ++i)
        EXPECT_LT(std::abs(lambda(i)), 1e-12 * largest) << "eigenvalue " << i;
    for (int i = 6; i < 12; ++i)
        EXPECT_GT(lambda(i), 1e-3 * largest) << "eigenvalue " << i;
}

TEST(TimoshenkoStiffness, CantileverFlexibilityIsTheTimoshenkoClosedForm) {
    for (double l : {kLength, 100.0}) {
        const BeamSection s = test_section();
        const Mat12 k = timoshenko_local_stiffness(s, l);
        const Mat6 flexibility = k.block<6, 6>(6, 6).inverse();
        const Mat6 expected = cantilever_flexibility(s, l);
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j)
                EXPECT_NEAR(flexibility(i, j), expected(i, j),
                            1e-12 * std::abs(expected(i, i)) + 1e-18)
                    << "entry (" << i << ", " << j << "), l = " << l;
    }
}

// The same statements as physical load cases, with the sign conventions spelled out.
TEST(TimoshenkoStiffness, TipLoadsDeflectAlongTheLoadWithTheClosedFormValues) {
    const BeamSection s = test_section();
    const double l = kLength, p = 0.5;
    const Mat6 k22 = timoshenko_local_stiffness(s, l).block<6, 6>(6, 6);
    const auto tip = [&](const Vec6& load) { return Vec6(k22.fullPivLu().solve(load)); };

    const Vec6 along_y = tip((Vec6() << 0, p, 0, 0, 0, 0).finished());
    EXPECT_NEAR(along_y(1),
                p * l * l * l / (3 * s.bending_stiffness_z_Nmm2) + p * l / s.shear_stiffness_y_N,
                1e-14);
    EXPECT_NEAR(along_y(5), p * l * l / (2 * s.bending_stiffness_z_Nmm2), 1e-14);  // turns about +z
    EXPECT_GT(along_y(1), 0.0);

    const Vec6 along_z = tip((Vec6() << 0, 0, p, 0, 0, 0).finished());
    EXPECT_NEAR(along_z(2),
                p * l * l * l / (3 * s.bending_stiffness_y_Nmm2) + p * l / s.shear_stiffness_z_N,
                1e-14);
    EXPECT_NEAR(along_z(4), -p * l * l / (2 * s.bending_stiffness_y_Nmm2),
                1e-14);  // turns about -y
    EXPECT_GT(along_z(2), 0.0);

    const Vec6 twist = tip((Vec6() << 0, 0, 0, p, 0, 0).finished());
    EXPECT_NEAR(twist(3), p * l / s.torsional_stiffness_Nmm2, 1e-15);  // theta = T l / GJ

    const Vec6 pull = tip((Vec6() << p, 0, 0, 0, 0, 0).finished());
    EXPECT_NEAR(pull(0), p * l / s.axial_stiffness_N, 1e-16);  // u = N l / EA

    // A pure end moment bends without shear: theta = M l / EI, v = M l^2 / 2EI.
    const Vec6 moment_z = tip((Vec6() << 0, 0, 0, 0, 0, p).finished());
    EXPECT_NEAR(moment_z(5), p * l / s.bending_stiffness_z_Nmm2, 1e-15);
    EXPECT_NEAR(moment_z(1), p * l * l / (2 * s.bending_stiffness_z_Nmm2), 1e-15);
}

// kappa G A -> infinity: phi = 0 and the classical Euler-Bernoulli entries 12EI/l^3, 6EI/l^2,
// 4EI/l, 2EI/l (Przemieniecki Eq. 5.115 with phi = 0), and the tip deflection P l^3 / 3EI.
TEST(TimoshenkoStiffness, InfiniteShearStiffnessGivesEulerBernoulli) {
    BeamSection s = test_section();
    s.shear_stiffness_y_N = s.shear_stiffness_z_N = std::numeric_limits<double>::infinity();
    const double l = kLength, ez = s.bending_stiffness_z_Nmm2, ey = s.bending_stiffness_y_Nmm2;
    const Mat12 k = timoshenko_local_stiffness(s, l);
    ASSERT_TRUE(k.allFinite());
    EXPECT_DOUBLE_EQ(k(1, 1), 12 * ez / (l * l * l));
    EXPECT_DOUBLE_EQ(k(1, 5), 6 * ez / (l * l));
    EXPECT_DOUBLE_EQ(k(5, 5), 4 * ez / l);
    EXPECT_DOUBLE_EQ(k(5, 11), 2 * ez / l);
    EXPECT_DOUBLE_EQ(k(2, 2), 12 * ey / (l * l * l));
    EXPECT_DOUBLE_EQ(k(2, 4), -6 * ey / (l * l));
    EXPECT_DOUBLE_EQ(k(4, 4), 4 * ey / l);
    EXPECT_DOUBLE_EQ(k(4, 10), 2 * ey / l);
    const Mat6 flexibility = k.block<6, 6>(6, 6).inverse();
    EXPECT_NEAR(flexibility(1, 1), l * l * l / (3 * ez), 1e-12 * l * l * l / ez);
    EXPECT_NEAR(flexibility(2, 2), l * l * l / (3 * ey), 1e-12 * l * l * l / ey);
    // And a very stiff but finite shear stiffness approaches it continuously.
    BeamSection stiff = test_section();
    stiff.shear_stiffness_y_N = stiff.shear_stiffness_z_N = 1e12;
    EXPECT_TRUE(
        matrices_near(timoshenko_local_stiffness(stiff, l), k, 1e-6 * k.cwiseAbs().maxCoeff()));
}

TEST(TimoshenkoMass, IsSymmetricPositiveDefinite) {
    const Mat12 m = timoshenko_local_mass(test_section(), kLength);
    EXPECT_TRUE(matrices_near(m, m.transpose(), 0.0));
    const Eigen::SelfAdjointEigenSolver<Mat12> eig(m);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
}

// Kinetic-energy checks T = 1/2 u^T M u for rigid motions, which the cubic/linear interpolation
// represents exactly: translation -> rho A l; spin about the axis -> rho J l; rotation about z
// (y) through node 1 -> int rho A x^2 dx + int rho I dx = rho A l^3 / 3 + rho I_z (I_y) l.
TEST(TimoshenkoMass, RigidMotionsCarryTheExactMassAndInertia) {
    const BeamSection s = test_section();
    for (double l : {kLength, 80.0}) {
        const Mat12 m = timoshenko_local_mass(s, l);
        const Eigen::Matrix<double, 12, 6> r = rigid_body_modes(l);
        const double rho_a = s.mass_per_length_t_per_mm;
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(r.col(c).dot(m * r.col(c)), rho_a * l, 1e-14 * rho_a * l) << "axis " << c;
        EXPECT_NEAR(r.col(3).dot(m * r.col(3)), s.polar_inertia_t_mm * l,
                    1e-14 * s.polar_inertia_t_mm * l);
        const double about_y = rho_a * l * l * l / 3.0 + s.rotary_inertia_y_t_mm * l;
        const double about_z = rho_a * l * l * l / 3.0 + s.rotary_inertia_z_t_mm * l;
        EXPECT_NEAR(r.col(4).dot(m * r.col(4)), about_y, 1e-13 * about_y) << "l = " << l;
        EXPECT_NEAR(r.col(5).dot(m * r.col(5)), about_z, 1e-13 * about_z) << "l = " << l;
    }
}

TEST(TimoshenkoMass, ZeroMassPerLengthGivesAZeroMatrix) {
    BeamSection s = test_section();
    s.mass_per_length_t_per_mm = 0.0;
    s.rotary_inertia_y_t_mm = s.rotary_inertia_z_t_mm = s.polar_inertia_t_mm = 0.0;
    const Mat12 m = timoshenko_local_mass(s, kLength);
    EXPECT_TRUE(m.allFinite());
    EXPECT_EQ(m.cwiseAbs().maxCoeff(), 0.0);
}

// Eq. (4.3): e1 along the element, e2 = (z x e1)/|z x e1| (horizontal), e3 = e1 x e2.
TEST(ReferenceElementFrame, IsRightHandedWithAHorizontalSecondAxis) {
    Random rng(11);
    for (int i = 0; i < 200; ++i) {
        const Eigen::Vector3d a = rng.vector(-100, 100);
        const Eigen::Vector3d d = rng.unit_vector();
        const double length = rng.uniform(1.0, 50.0);
        const Eigen::Matrix3d e = reference_element_frame(a, a + length * d);
        EXPECT_TRUE(matrices_near(e.transpose() * e, Eigen::Matrix3d::Identity(), 1e-14));
        EXPECT_NEAR(e.determinant(), 1.0, 1e-14);
        EXPECT_TRUE(matrices_near(e.col(0), d, 1e-14));
        const Eigen::Vector3d horizontal = Eigen::Vector3d::UnitZ().cross(d).normalized();
        EXPECT_TRUE(matrices_near(e.col(1), horizontal, 1e-13));
        EXPECT_TRUE(matrices_near(e.col(2), d.cross(horizontal), 1e-13));
        EXPECT_GE(e(2, 2), 0.0);  // e3 points upwards
    }
}

// Hand value: an element along +x has the identity frame; along +y: e2 = z x y = -x, e3 = z.
TEST(ReferenceElementFrame, HorizontalHandValues) {
    EXPECT_TRUE(matrices_near(reference_element_frame({1, 2, 3}, {5, 2, 3}),
                              Eigen::Matrix3d::Identity(), 0.0));
    Eigen::Matrix3d along_y;
    along_y.col(0) = Eigen::Vector3d(0, 1, 0);
    along_y.col(1) = Eigen::Vector3d(-1, 0, 0);
    along_y.col(2) = Eigen::Vector3d(0, 0, 1);
    EXPECT_TRUE(matrices_near(reference_element_frame({0, 0, 0}, {0, 7, 0}), along_y, 1e-15));
}

// App. F's vertical special case: rows of Lambda = frame^T are [0 0 1; 0 1 0; -1 0 0] for +z
// and [0 0 -1; 0 1 0; 1 0 0] for -z. Both are right-handed (e1 x e2 = e3).
TEST(ReferenceElementFrame, VerticalElementsFollowAppendixF) {
    Eigen::Matrix3d lambda_up, lambda_down;
    lambda_up << 0, 0, 1, 0, 1, 0, -1, 0, 0;
    lambda_down << 0, 0, -1, 0, 1, 0, 1, 0, 0;
    const Eigen::Vector3d a(3, -4, 10);
    EXPECT_TRUE(matrices_near(reference_element_frame(a, a + Eigen::Vector3d(0, 0, 25)).transpose(),
                              lambda_up, 0.0));
    EXPECT_TRUE(matrices_near(reference_element_frame(a, a - Eigen::Vector3d(0, 0, 25)).transpose(),
                              lambda_down, 0.0));
    EXPECT_NEAR(lambda_up.determinant(), 1.0, 0.0);
    EXPECT_NEAR(lambda_down.determinant(), 1.0, 0.0);
}

}  // namespace
}  // namespace scopekin::model
