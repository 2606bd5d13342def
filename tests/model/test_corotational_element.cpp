// Co-rotational element (model/beam/corotational_element.hpp) against finite differences and
// against the invariances that define it. Global variables: [dx_a, dw_a, dx_b, dw_b], where a
// rotation variable is a spatial spin, R -> exp(S(dw)) R.
//
// Configurations are random but seeded: node positions perturbed by up to 2 mm on a 15 mm
// element, node rotations up to 0.5 rad, all on top of a large rigid rotation (up to 170 deg)
// and translation, so the element is far from its reference pose.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>

#include "model/beam/corotational_element.hpp"
#include "model/beam/timoshenko_element.hpp"
#include "model_test_support.hpp"

namespace scopekin::model {
namespace {

using testing::matrices_near;
using testing::Random;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

BeamSection test_section() {
    return BeamSection{.axial_stiffness_N = 3000.0,
                       .bending_stiffness_y_Nmm2 = 20000.0,
                       .bending_stiffness_z_Nmm2 = 35000.0,
                       .torsional_stiffness_Nmm2 = 7000.0,
                       .shear_stiffness_y_N = 250.0,
                       .shear_stiffness_z_N = 300.0,
                       .mass_per_length_t_per_mm = 1.2e-6};
}
constexpr double kLength = 15.0;

// Rotations built with Eigen's AngleAxis, not with the model's rotation_exp.
Mat3 spin(const Vec3& w) {
    const double t = w.norm();
    return t == 0.0 ? Mat3::Identity() : Mat3(Eigen::AngleAxisd(t, w / t));
}

struct Pose {
    Vec3 xa, xb;
    Mat3 ra, rb;
};

/// The pose after the global variable `var` (0..11) is changed by `h`.
Pose perturbed(const Pose& p, int var, double h) {
    Pose q = p;
    const Vec3 delta = h * Vec3::Unit(var % 3);
    switch (var / 3) {
        case 0: q.xa += delta; break;
        case 1: q.ra = spin(delta) * p.ra; break;
        case 2: q.xb += delta; break;
        default: q.rb = spin(delta) * p.rb; break;
    }
    return q;
}

struct Fixture {
    Vec3 a0, b0;
    CorotationalReference ref;
    Pose deformed;
};

/// A random element (direction `direction`, or random if zero) and a random deformed pose of it.
Fixture make_fixture(Random& rng, Vec3 direction = Vec3::Zero(), double rigid_angle = -1.0) {
    Fixture f;
    f.a0 = rng.vector(-50, 50);
    if (direction.norm() == 0.0) direction = rng.unit_vector();
    f.b0 = f.a0 + kLength * direction.normalized();
    f.ref = make_corotational_reference(test_section(), f.a0, f.b0);
    const Mat3 q =
        rng.rotation(rigid_angle >= 0.0 ? rigid_angle : rng.uniform(0.0, 170.0 * M_PI / 180.0));
    const Vec3 t = rng.vector(-100, 100);
    f.deformed.xa = t + q * (f.a0 + rng.vector(-2, 2));
    f.deformed.xb = t + q * (f.b0 + rng.vector(-2, 2));
    f.deformed.ra = q * spin(rng.uniform(0.0, 0.5) * rng.unit_vector());
    f.deformed.rb = q * spin(rng.uniform(0.0, 0.5) * rng.unit_vector());
    return f;
}

CorotationalResponse respond(const CorotationalReference& ref, const Pose& p, bool tangent = true) {
    return corotational_response(ref, p.xa, p.ra, p.xb, p.rb, tangent);
}

/// Scales translation variables by l (and their force rows by l), so that every entry of a
/// 12 x 12 tangent has the unit N mm and one relative tolerance fits all blocks.
Mat12 dimensionless(const Mat12& k, double l) {
    Mat12 s = Mat12::Identity();
    for (int i : {0, 1, 2, 6, 7, 8})
        s(i, i) = l;
    return s * k * s;
}

/// 12 x 12 block-diagonal rotation.
Mat12 block_rotation(const Mat3& q) {
    Mat12 t = Mat12::Zero();
    for (int b = 0; b < 4; ++b)
        t.block<3, 3>(3 * b, 3 * b) = q;
    return t;
}

// (a) B = d(deformation)/d(global variables), central differences with step 1e-6 (rad) and
// 1e-6 l (mm): truncation ~1e-12, round-off ~1e-10. Rows/columns are made dimensionless.
TEST(CorotationalElement, BMatrixMatchesFiniteDifferencesOfTheDeformation) {
    Random rng(21);
    for (int sample = 0; sample < 30; ++sample) {
        const Fixture f = make_fixture(rng);
        const auto deformation = [&](const Pose& p) {
            return corotational_kinematics(f.ref, p.xa, p.ra, p.xb, p.rb).deformation;
        };
        Mat7x12 numeric;
        for (int var = 0; var < 12; ++var) {
            const bool translation = (var / 3) % 2 == 0;
            const double h = translation ? 1e-6 * kLength : 1e-6;
            numeric.col(var) = (deformation(perturbed(f.deformed, var, h)) -
                                deformation(perturbed(f.deformed, var, -h))) /
                               (2 * h);
        }
        Mat7x12 b = corotational_kinematics(f.ref, f.deformed.xa, f.deformed.ra, f.deformed.xb,
                                            f.deformed.rb)
                        .b_matrix;
        for (Mat7x12* m : {&b, &numeric}) {
            m->row(0) /= kLength;
            for (int c : {0, 1, 2, 6, 7, 8})
                m->col(c) *= kLength;
        }
        EXPECT_TRUE(matrices_near(b, numeric, 1e-7)) << "sample " << sample;
    }
}

// (b) material + geometric tangent = d(internal force)/d(global variables), central
// differences (step 1e-6: error ~1e-10 relative). The relative tolerance 1e-5 on the largest
// entry also admits a geometric tangent that is itself a forward difference (relative step 1e-7).
TEST(CorotationalElement, TangentMatchesFiniteDifferencesOfTheInternalForce) {
    Random rng(22);
    for (int sample = 0; sample < 30; ++sample) {
        const Fixture f = make_fixture(rng);
        Mat12 numeric;
        for (int var = 0; var < 12; ++var) {
            const bool translation = (var / 3) % 2 == 0;
            const double h = translation ? 1e-6 * kLength : 1e-6;
            numeric.col(var) =
                (respond(f.ref, perturbed(f.deformed, var, h), false).internal_force -
                 respond(f.ref, perturbed(f.deformed, var, -h), false).internal_force) /
                (2 * h);
        }
        const CorotationalResponse r = respond(f.ref, f.deformed);
        const Mat12 analytic = dimensionless(r.material_tangent + r.geometric_tangent, kLength);
        const Mat12 expected = dimensionless(numeric, kLength);
        EXPECT_TRUE(matrices_near(analytic, expected, 1e-5 * expected.cwiseAbs().maxCoeff()))
            << "sample " << sample;
        // The material part alone is B^T K_l B: symmetric.
        EXPECT_TRUE(matrices_near(r.material_tangent, r.material_tangent.transpose(),
                                  1e-12 * r.material_tangent.cwiseAbs().maxCoeff()));
    }
}

// The internal force is the gradient of the strain energy 1/2 p^T K_l p (p = deformation).
TEST(CorotationalElement, InternalForceIsTheGradientOfTheStrainEnergy) {
    Random rng(23);
    for (int sample = 0; sample < 20; ++sample) {
        const Fixture f = make_fixture(rng);
        const auto energy = [&](const Pose& p) {
            const Vec7 d = corotational_kinematics(f.ref, p.xa, p.ra, p.xb, p.rb).deformation;
            return 0.5 * d.dot(f.ref.local_stiffness * d);
        };
        const Vec12 force = respond(f.ref, f.deformed, false).internal_force;
        for (int var = 0; var < 12; ++var) {
            const bool translation = (var / 3) % 2 == 0;
            const double h = translation ? 1e-5 * kLength : 1e-5;
            const double numeric =
                (energy(perturbed(f.deformed, var, h)) - energy(perturbed(f.deformed, var, -h))) /
                (2 * h);
            const double scale =
                translation ? force.cwiseAbs().maxCoeff() : force.cwiseAbs().maxCoeff() * kLength;
            EXPECT_NEAR(force(var), numeric, 1e-6 * scale)
                << "sample " << sample << " variable " << var;
        }
    }
}

// (c) A rigid motion of the stress-free element (translation plus rotation of any angle, up to
// a half turn, about a random axis; also for App. F's vertical reference frames) leaves it
// stress free: zero deformation and zero internal force.
TEST(CorotationalElement, RigidBodyMotionIsStressFree) {
    Random rng(24);
    for (const Vec3& direction :
         {Vec3(Vec3::Zero()), Vec3(Vec3::UnitX()), Vec3(Vec3::UnitZ()), Vec3(-Vec3::UnitZ())}) {
        for (double angle_deg : {0.0, 1e-6, 30.0, 90.0, 170.0, 179.9, 180.0}) {
            const Fixture f = make_fixture(rng, direction);
            const Mat3 q = rng.rotation(angle_deg * M_PI / 180.0);
            const Vec3 t = rng.vector(-500, 500);
            const Pose moved{t + q * f.a0, t + q * f.b0, q, q};
            const CorotationalResponse r = respond(f.ref, moved);
            EXPECT_LT(r.kinematics.deformation.cwiseAbs().maxCoeff(), 1e-12) << angle_deg << " deg";
            // Round-off on a 500 mm translation is ~1e-13 mm, times EA / l = 200 N/mm.
            EXPECT_LT(r.internal_force.cwiseAbs().maxCoeff(), 1e-9) << angle_deg << " deg";
            EXPECT_NEAR(r.kinematics.length_mm, kLength, 1e-12);
            // The current frame is the reference frame carried along: R_r = Q E0.
            EXPECT_TRUE(matrices_near(r.kinematics.frame, q * f.ref.frame, 1e-12))
                << angle_deg << " deg";
        }
    }
}

// At the undeformed reference the co-rotational tangent is the linear Timoshenko stiffness
// (Eq. 4.2) rotated into the global frame: T K_local T^T with T = diag(E0, E0, E0, E0); the
// geometric part vanishes because no force acts.
TEST(CorotationalElement, TangentAtTheReferenceIsTheRotatedTimoshenkoStiffness) {
    Random rng(25);
    for (int sample = 0; sample < 10; ++sample) {
        const Fixture f = make_fixture(rng, sample == 0 ? Vec3(Vec3::UnitZ()) : Vec3::Zero());
        const CorotationalResponse r =
            respond(f.ref, {f.a0, f.b0, Mat3::Identity(), Mat3::Identity()});
        const Mat12 t = block_rotation(f.ref.frame);
        const Mat12 expected =
            t * timoshenko_local_stiffness(test_section(), kLength) * t.transpose();
        EXPECT_TRUE(
            matrices_near(r.material_tangent, expected, 1e-11 * expected.cwiseAbs().maxCoeff()));
        EXPECT_LT(r.geometric_tangent.cwiseAbs().maxCoeff(), 1e-12);
    }
}

// (d) Objectivity: moving a deformed element rigidly (x -> t + Q x, R -> Q R) leaves its
// deformation unchanged and rotates its internal forces and tangents with Q.
TEST(CorotationalElement, RigidMotionOfADeformedElementRotatesItsForces) {
    Random rng(26);
    for (int sample = 0; sample < 20; ++sample) {
        const Fixture f = make_fixture(rng);
        const Mat3 q = rng.rotation(rng.uniform(0.0, M_PI));
        const Vec3 t = rng.vector(-100, 100);
        const Pose moved{t + q * f.deformed.xa, t + q * f.deformed.xb, q * f.deformed.ra,
                         q * f.deformed.rb};
        const CorotationalResponse before = respond(f.ref, f.deformed);
        const CorotationalResponse after = respond(f.ref, moved);
        EXPECT_TRUE(
            matrices_near(after.kinematics.deformation, before.kinematics.deformation, 1e-12));
        const Mat12 rot = block_rotation(q);
        const double force_scale = before.internal_force.cwiseAbs().maxCoeff();
        EXPECT_TRUE(
            matrices_near(after.internal_force, rot * before.internal_force, 1e-10 * force_scale));
        const Mat12 k_before = before.material_tangent + before.geometric_tangent;
        const Mat12 k_after = after.material_tangent + after.geometric_tangent;
        const Mat12 expected = dimensionless(rot * k_before * rot.transpose(), kLength);
        EXPECT_TRUE(matrices_near(dimensionless(k_after, kLength), expected,
                                  1e-5 * expected.cwiseAbs().maxCoeff()));
    }
}

// Consequence of translation and rotation invariance of the strain energy: the nodal forces of
// an element are self-equilibrated, f_a + f_b = 0 and m_a + m_b + x_a x f_a + x_b x f_b = 0.
TEST(CorotationalElement, InternalForcesAreSelfEquilibrated) {
    Random rng(27);
    for (int sample = 0; sample < 30; ++sample) {
        const Fixture f = make_fixture(rng);
        const Vec12 g = respond(f.ref, f.deformed, false).internal_force;
        const Vec3 fa = g.segment<3>(0), ma = g.segment<3>(3), fb = g.segment<3>(6),
                   mb = g.segment<3>(9);
        const double scale =
            fa.norm() * (f.deformed.xa.norm() + f.deformed.xb.norm()) + ma.norm() + mb.norm();
        EXPECT_LT((fa + fb).norm(), 1e-12 * fa.norm() + 1e-12) << "sample " << sample;
        EXPECT_LT((ma + mb + f.deformed.xa.cross(fa) + f.deformed.xb.cross(fb)).norm(),
                  1e-10 * scale)
            << "sample " << sample;
    }
}

// Hand value: stretch along the axis by du with no rotation: deformation [du, 0, 0], axial
// force N = EA du / l, nodal forces -N e1 at a and +N e1 at b.
TEST(CorotationalElement, PureStretchHandValue) {
    const Vec3 a0(0, 0, 0), b0(kLength, 0, 0);
    const CorotationalReference ref = make_corotational_reference(test_section(), a0, b0);
    const double du = 0.3;
    const CorotationalResponse r =
        respond(ref, {a0, b0 + Vec3(du, 0, 0), Mat3::Identity(), Mat3::Identity()});
    Vec7 expected_deformation = Vec7::Zero();
    expected_deformation(0) = du;
    EXPECT_TRUE(matrices_near(r.kinematics.deformation, expected_deformation, 1e-15));
    const double n = test_section().axial_stiffness_N * du / kLength;  // 60 N
    Vec12 expected_force = Vec12::Zero();
    expected_force(0) = -n;
    expected_force(6) = n;
    EXPECT_TRUE(matrices_near(r.internal_force, expected_force, 1e-12));
}

}  // namespace
}  // namespace scopekin::model
