// SO(3) helpers of the co-rotational beam (model/beam/rotation.hpp). References: Eigen's
// AngleAxis (an independent Rodrigues implementation), the cross product, the definition of the
// principal logarithm, central finite differences, and the polar decomposition.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "model/beam/rotation.hpp"
#include "model_test_support.hpp"

namespace scopekin::model {
namespace {

using testing::matrices_near;
using testing::Random;

Mat3 angle_axis(const Vec3& theta) {
    const double t = theta.norm();
    if (t == 0.0) return Mat3::Identity();
    return Eigen::AngleAxisd(t, theta / t).toRotationMatrix();
}

TEST(Rotation, SkewIsTheCrossProduct) {
    Random rng(1);
    for (int i = 0; i < 20; ++i) {
        const Vec3 v = rng.vector(-3, 3), w = rng.vector(-3, 3);
        EXPECT_TRUE(matrices_near(skew(v) * w, v.cross(w), 1e-14));
        EXPECT_TRUE(matrices_near(skew(v).transpose(), -skew(v), 0.0));
    }
}

// exp against Eigen's AngleAxis for magnitudes from 1e-10 (Taylor branch) to beyond 2 pi.
TEST(Rotation, ExpMatchesAngleAxisAndIsARotation) {
    Random rng(2);
    for (double magnitude : {0.0, 1e-10, 1e-8, 1e-6, 0.3, 1.0, 2.0, M_PI - 1e-7, M_PI, 4.0, 7.0}) {
        for (int i = 0; i < 10; ++i) {
            const Vec3 theta = magnitude * rng.unit_vector();
            const Mat3 r = rotation_exp(theta);
            EXPECT_TRUE(matrices_near(r, angle_axis(theta), 1e-14)) << "|theta| = " << magnitude;
            EXPECT_TRUE(matrices_near(r.transpose() * r, Mat3::Identity(), 1e-14));
            EXPECT_NEAR(r.determinant(), 1.0, 1e-14);
        }
    }
}

// Principal logarithm: log(exp(theta)) = theta whenever |theta| < pi, including the two
// delicate regimes |theta| -> 0 (axial vector ~ 2 theta) and |theta| -> pi (axial vector -> 0).
TEST(Rotation, LogInvertsExpBelowPi) {
    Random rng(3);
    for (double magnitude : {1e-12, 1e-10, 1e-7, 1e-6, 2e-6, 1e-4, 0.1, 1.0, 2.5, 3.0, M_PI - 2e-3,
                             M_PI - 1e-3, M_PI - 5e-4, M_PI - 1e-5, M_PI - 1e-7}) {
        for (int i = 0; i < 20; ++i) {
            const Vec3 theta = magnitude * rng.unit_vector();
            // The input rotation comes from Eigen, so the round trip does not only test exp against log.
            const Vec3 back = rotation_log(angle_axis(theta));
            // Relative accuracy ~1e-15 away from pi; at pi - 1e-7 the axis is taken from the symmetric
            // part (R + R^T)/2 - cos t I = (1 - cos t) n n^T, whose entries carry ~1e-16 round-off: fine.
            EXPECT_LE((back - theta).norm(), 1e-12 * magnitude)
                << "|theta| = " << magnitude << ", theta = " << theta.transpose()
                << ", log = " << back.transpose();
        }
    }
}

// |theta| > pi: the principal value is the same rotation the short way round,
// theta - 2 pi theta/|theta| (so |log| <= pi).
TEST(Rotation, LogReturnsThePrincipalValueAbovePi) {
    Random rng(4);
    for (double magnitude : {M_PI + 1e-7, M_PI + 0.3, 5.0, 2.0 * M_PI - 0.1}) {
        const Vec3 n = rng.unit_vector();
        const Vec3 expected = (magnitude - 2.0 * M_PI) * n;
        EXPECT_LE((rotation_log(angle_axis(magnitude * n)) - expected).norm(), 1e-12)
            << "|theta| = " << magnitude;
    }
}

// Exactly pi: theta and -theta are the same rotation; either is a correct principal logarithm.
TEST(Rotation, LogAtExactlyPiGivesAHalfTurnAboutTheAxis) {
    Random rng(5);
    std::vector<Vec3> axes{Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ(), Vec3(1, 1, 0).normalized()};
    for (int i = 0; i < 20; ++i)
        axes.push_back(rng.unit_vector());
    for (const Vec3& n : axes) {
        // R = 2 n n^T - I exactly (Rodrigues at t = pi), no sin(pi) round-off in the input.
        const Mat3 r = 2.0 * n * n.transpose() - Mat3::Identity();
        const Vec3 theta = rotation_log(r);
        EXPECT_NEAR(theta.norm(), M_PI, 1e-12) << "axis " << n.transpose();
        EXPECT_NEAR(std::abs(theta.normalized().dot(n)), 1.0, 1e-12) << "axis " << n.transpose();
        EXPECT_TRUE(matrices_near(angle_axis(theta), r, 1e-12));
    }
}

// d/d(dw) log(exp(S(dw)) exp(S(theta))) at dw = 0 is T^-1(theta) (left spin). Central
// differences, step 1e-6: truncation ~h^2 = 1e-12, round-off ~1e-16/h = 1e-10.
TEST(Rotation, LeftJacobianInverseMatchesFiniteDifferencesOfLog) {
    Random rng(6);
    const double h = 1e-6;
    for (double magnitude : {0.0, 1e-9, 1e-5, 9e-5, 1.1e-4, 0.01, 0.5, 1.5, 2.5, 3.0}) {
        for (int i = 0; i < 5; ++i) {
            const Vec3 theta = magnitude * rng.unit_vector();
            const Mat3 r = angle_axis(theta);
            Mat3 numeric;
            for (int k = 0; k < 3; ++k) {
                const Vec3 dw = h * Vec3::Unit(k);
                numeric.col(k) =
                    (rotation_log(angle_axis(dw) * r) - rotation_log(angle_axis(-dw) * r)) /
                    (2.0 * h);
            }
            EXPECT_TRUE(matrices_near(left_jacobian_inverse(theta), numeric, 2e-8))
                << "|theta| = " << magnitude;
        }
    }
}

// Closed form at a hand-checkable point: theta = (pi/2) z. With t = pi/2, (t/2) cot(t/2) = pi/4,
// eta = (1 - pi/4) / (pi/2)^2 and S^2 = (pi/2)^2 diag(-1, -1, 0), so
// T^-1 = [[pi/4, pi/4, 0], [-pi/4, pi/4, 0], [0, 0, 1]].
TEST(Rotation, LeftJacobianInverseHandValue) {
    Mat3 expected;
    expected << M_PI / 4, M_PI / 4, 0, -M_PI / 4, M_PI / 4, 0, 0, 0, 1;
    EXPECT_TRUE(matrices_near(left_jacobian_inverse(Vec3(0, 0, M_PI / 2)), expected, 1e-15));
}

// Polar decomposition A = U P (P symmetric positive definite) has U = the nearest rotation;
// so a rotation times any SPD stretch projects back exactly onto that rotation.
TEST(Rotation, ReorthonormalizeRemovesASymmetricStretch) {
    Random rng(7);
    for (int i = 0; i < 20; ++i) {
        const Mat3 r = rng.rotation(rng.uniform(0.0, M_PI));
        const Mat3 q = rng.rotation(rng.uniform(0.0, M_PI));
        const Vec3 stretches = rng.vector(0.8, 1.2);
        const Mat3 p = q * stretches.asDiagonal() * q.transpose();
        EXPECT_TRUE(matrices_near(reorthonormalize(r * p), r, 1e-13));
        EXPECT_TRUE(matrices_near(reorthonormalize(r), r, 1e-15));
    }
}

// Drift of 1e-8 per entry (any direction): the result is orthonormal to round-off, right-handed,
// and within the drift of the input.
TEST(Rotation, ReorthonormalizeRepairsDrift) {
    Random rng(8);
    for (int i = 0; i < 20; ++i) {
        const Mat3 r = rng.rotation(rng.uniform(0.0, M_PI));
        Mat3 drifted = r;
        for (int k = 0; k < 9; ++k)
            drifted(k / 3, k % 3) += rng.uniform(-1e-8, 1e-8);
        const Mat3 fixed = reorthonormalize(drifted);
        EXPECT_TRUE(matrices_near(fixed.transpose() * fixed, Mat3::Identity(),
                                  4e-15));  // ~20 ulp of SVD round-off
        EXPECT_NEAR(fixed.determinant(), 1.0, 4e-15);
        EXPECT_TRUE(matrices_near(fixed, r, 3e-8));
    }
}

}  // namespace
}  // namespace scopekin::model
