// Gauss-Seidel contact solver instantiated with `float`: the firmware build of the template.
// Runs as GoogleTest on x86-64 / aarch64 and with portable_check's runner on Cortex-M4 (there it
// is compiled with the firmware flags: -fno-exceptions -fno-rtti, no heap).  Expected values are
// closed forms worked by hand (see tests/model/test_gauss_seidel_contact.cpp for the full double
// tests).  Storage is static: nothing on the heap, little on the stack.
#include <cstddef>

#include "contact/gauss_seidel_contact.hpp"
#include "portable_check.hpp"

namespace {

namespace sc = scopekin::contact;

constexpr std::size_t capacity = 4;
using Problem = sc::ContactProblem<float, capacity>;
using Forces = sc::ContactForces<float, capacity>;

bool near(float actual, float expected, float tolerance) {
    const float diff = actual - expected;
    return diff <= tolerance && -diff <= tolerance;
}

Problem problem{};
Forces forces{};

void set_diagonal(std::size_t a, float w_n, float w_t, float w_s) {
    problem.block(a, a) = {w_n, 0.0F, 0.0F, 0.0F, w_t, 0.0F, 0.0F, 0.0F, w_s};
}

void clear() {
    problem = Problem{};
    forces = Forces{};
}

sc::GaussSeidelSettings<float> until(float tolerance) {
    sc::GaussSeidelSettings<float> s{};
    s.mode = sc::SweepMode::until_converged;
    s.max_sweeps = 200;
    s.tolerance = tolerance;
    s.local_iterations = 40;
    return s;
}

}  // namespace

SCOPEKIN_TEST(GaussSeidelContactFloat, SingleContactStickAndSlip) {
    // W = diag(2, 0.5, 0.5), mu = 0.5.
    clear();
    problem.contact_count = 1;
    set_diagonal(0, 2.0F, 0.5F, 0.5F);
    problem.friction[0] = 0.5F;
    // Stick: q = (-1, 0.05, -0.02): f = -W^-1 q = (0.5, -0.1, 0.04).
    problem.free_displacement[0] = {-1.0F, 0.05F, -0.02F};
    auto report = sc::solve_contacts(problem, until(1e-6F), forces);
    SCOPEKIN_EXPECT_TRUE(report.status == sc::ContactSolveStatus::converged);
    SCOPEKIN_EXPECT_TRUE(report.states[0] == sc::ContactState::sticking);
    SCOPEKIN_EXPECT_TRUE(near(forces[0][0], 0.5F, 1e-6F));
    SCOPEKIN_EXPECT_TRUE(near(forces[0][1], -0.1F, 1e-6F));
    SCOPEKIN_EXPECT_TRUE(near(forces[0][2], 0.04F, 1e-6F));
    // Slip: q = (-1, 0.6, -0.8): f = (0.5, -0.15, 0.2).
    problem.free_displacement[0] = {-1.0F, 0.6F, -0.8F};
    report = sc::solve_contacts(problem, until(1e-6F), forces);
    SCOPEKIN_EXPECT_TRUE(report.states[0] == sc::ContactState::slipping);
    SCOPEKIN_EXPECT_TRUE(near(forces[0][0], 0.5F, 1e-6F));
    SCOPEKIN_EXPECT_TRUE(near(forces[0][1], -0.15F, 1e-6F));
    SCOPEKIN_EXPECT_TRUE(near(forces[0][2], 0.2F, 1e-6F));
    // Separation: q_n = 0.2 > 0: f = 0.
    problem.free_displacement[0] = {0.2F, 0.6F, -0.8F};
    report = sc::solve_contacts(problem, until(1e-6F), forces);
    SCOPEKIN_EXPECT_TRUE(report.states[0] == sc::ContactState::separated);
    SCOPEKIN_EXPECT_TRUE(forces[0][0] == 0.0F);
}

SCOPEKIN_TEST(GaussSeidelContactFloat, TwoCoupledFrictionlessContacts) {
    // W_nn = [[2, 1], [1, 2]] (tangential blocks identity, mu = 0), q_n = (-1, -1):
    // both active, f_n = W_nn^-1 (1, 1) = (1/3, 1/3).  With q_n = (-1, 1): contact 1 opens,
    // f_n = (0.5, 0) and delta_n1 = 1 + 0.5 = 1.5 >= 0.
    clear();
    problem.contact_count = 2;
    set_diagonal(0, 2.0F, 1.0F, 1.0F);
    set_diagonal(1, 2.0F, 1.0F, 1.0F);
    problem.block(0, 1)[0] = 1.0F;
    problem.block(1, 0)[0] = 1.0F;
    problem.free_displacement[0] = {-1.0F, 0.0F, 0.0F};
    problem.free_displacement[1] = {-1.0F, 0.0F, 0.0F};
    auto report = sc::solve_contacts(problem, until(1e-7F), forces);
    SCOPEKIN_EXPECT_TRUE(report.status == sc::ContactSolveStatus::converged);
    SCOPEKIN_EXPECT_TRUE(near(forces[0][0], 1.0F / 3.0F, 1e-6F));
    SCOPEKIN_EXPECT_TRUE(near(forces[1][0], 1.0F / 3.0F, 1e-6F));
    SCOPEKIN_EXPECT_TRUE(report.residuals.complementarity <= 1e-6F);
    problem.free_displacement[1] = {1.0F, 0.0F, 0.0F};
    report = sc::solve_contacts(problem, until(1e-7F), forces);
    SCOPEKIN_EXPECT_TRUE(near(forces[0][0], 0.5F, 1e-6F));
    SCOPEKIN_EXPECT_TRUE(forces[1][0] == 0.0F);
    SCOPEKIN_EXPECT_TRUE(report.states[1] == sc::ContactState::separated);
}

SCOPEKIN_TEST(GaussSeidelContactFloat, FixedModeDoesExactlyTheRequestedSweeps) {
    clear();
    problem.contact_count = 3;
    for (std::size_t a = 0; a < 3; ++a) {
        set_diagonal(a, 1.0F, 1.0F, 1.0F);
        problem.friction[a] = 0.3F;
        problem.free_displacement[a] = {-0.5F, 0.4F, -0.1F};
    }
    problem.block(0, 1)[0] = 0.3F;
    problem.block(1, 0)[0] = 0.3F;
    problem.block(1, 2)[4] = 0.2F;
    problem.block(2, 1)[4] = 0.2F;
    sc::GaussSeidelSettings<float> fixed{};
    fixed.mode = sc::SweepMode::fixed;
    fixed.max_sweeps = 5;
    fixed.tolerance = 0.0F;
    fixed.local_iterations = 20;
    const auto report = sc::solve_contacts(problem, fixed, forces);
    SCOPEKIN_EXPECT_TRUE(report.status == sc::ContactSolveStatus::fixed_sweeps_done);
    SCOPEKIN_EXPECT_EQ(report.sweeps, std::size_t{5});
    SCOPEKIN_EXPECT_TRUE(report.residuals.cone_violation <= 1e-6F);
}

SCOPEKIN_TEST(GaussSeidelContactFloat, InvalidCountLeavesForcesUntouched) {
    clear();
    problem.contact_count = capacity + 1;
    forces[0] = {3.0F, 0.0F, 0.0F};
    const auto report = sc::solve_contacts(problem, until(1e-6F), forces);
    SCOPEKIN_EXPECT_TRUE(report.status == sc::ContactSolveStatus::invalid_input);
    SCOPEKIN_EXPECT_EQ(report.sweeps, std::size_t{0});
    SCOPEKIN_EXPECT_TRUE(forces[0][0] == 3.0F);
}
