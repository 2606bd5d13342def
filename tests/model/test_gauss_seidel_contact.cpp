// Gauss-Seidel frictional contact solver (firmware/contact/gauss_seidel_contact.hpp), double.
// Every expected number is independent of the solver: closed forms worked by hand (comments),
// an active-set enumeration written here with Eigen, and the contact conditions themselves checked
// on delta = W f + delta_free recomputed here with Eigen.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iostream>
#include <memory>
#include <random>
#include <vector>

#include "contact/gauss_seidel_contact.hpp"

namespace {

namespace sc = scopekin::contact;

constexpr std::size_t max_contacts = 20;
using Problem = sc::ContactProblem<double, max_contacts>;
using Forces = sc::ContactForces<double, max_contacts>;
using Settings = sc::GaussSeidelSettings<double>;
using sc::ContactState;

Settings converge_to(double tolerance, std::size_t max_sweeps = 20000) {
    Settings s{};
    s.mode = sc::SweepMode::until_converged;
    s.tolerance = tolerance;
    s.max_sweeps = max_sweeps;
    s.local_iterations = 60;
    return s;
}

Forces zero_forces() {
    Forces f{};
    for (auto& v : f) {
        v = {0.0, 0.0, 0.0};
    }
    return f;
}

// Heap-allocated because a 20-contact problem holds 3600 doubles.
std::unique_ptr<Problem> make_problem(const Eigen::MatrixXd& w, const Eigen::VectorXd& q,
                                      const Eigen::VectorXd& mu) {
    auto p = std::make_unique<Problem>();
    const auto n = static_cast<std::size_t>(mu.size());
    p->contact_count = n;
    for (std::size_t i = 0; i < 3 * n; ++i) {
        for (std::size_t j = 0; j < 3 * n; ++j) {
            p->delassus_entry(i, j) = w(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
        }
    }
    for (std::size_t a = 0; a < n; ++a) {
        for (std::size_t k = 0; k < 3; ++k) {
            p->free_displacement[a][k] = q(static_cast<Eigen::Index>(3 * a + k));
        }
        p->friction[a] = mu(static_cast<Eigen::Index>(a));
    }
    return p;
}

Eigen::VectorXd stacked(const Forces& f, std::size_t n) {
    Eigen::VectorXd v(static_cast<Eigen::Index>(3 * n));
    for (std::size_t a = 0; a < n; ++a) {
        for (std::size_t k = 0; k < 3; ++k) {
            v(static_cast<Eigen::Index>(3 * a + k)) = f[a][k];
        }
    }
    return v;
}

// One contact, local solve through the full solver.
struct Single {
    Forces f;
    sc::ContactSolveReport<double, max_contacts> report;
};

Single solve_single(const Eigen::Matrix3d& w, const Eigen::Vector3d& q, double mu) {
    const auto p = make_problem(w, q, Eigen::VectorXd::Constant(1, mu));
    Single s{zero_forces(), {}};
    s.report = sc::solve_contacts(*p, converge_to(1e-12), s.f);
    return s;
}

// Random well-posed problem: W = J M^-1 J^T + r I, J (3n x m) with N(0, 1/m) entries, m = 2*3n
// generalised coordinates, M^-1 diagonal in [0.5, 2] (1/t), r = 1e-3 (mm/N).  W_ii ~ 1 mm/N.
struct RandomProblem {
    Eigen::MatrixXd w;
    Eigen::VectorXd q;
    Eigen::VectorXd mu;
};

RandomProblem random_problem(std::mt19937_64& rng, std::size_t n, bool frictionless) {
    const auto rows = static_cast<Eigen::Index>(3 * n);
    const Eigen::Index m = 2 * rows;
    std::normal_distribution<double> normal(0.0, 1.0 / std::sqrt(static_cast<double>(m)));
    std::uniform_real_distribution<double> inv_mass(0.5, 2.0);
    std::uniform_real_distribution<double> gap(-1.0, 0.5);
    std::uniform_real_distribution<double> tangential(-1.0, 1.0);
    std::uniform_real_distribution<double> friction(0.0, 1.0);
    Eigen::MatrixXd j(rows, m);
    for (Eigen::Index r = 0; r < rows; ++r) {
        for (Eigen::Index c = 0; c < m; ++c) {
            j(r, c) = normal(rng);
        }
    }
    Eigen::VectorXd minv(m);
    for (Eigen::Index c = 0; c < m; ++c) {
        minv(c) = inv_mass(rng);
    }
    RandomProblem out;
    out.w = j * minv.asDiagonal() * j.transpose();
    out.w += 1e-3 * Eigen::MatrixXd::Identity(rows, rows);
    out.w = 0.5 * (out.w + out.w.transpose()).eval();
    out.q.resize(rows);
    out.mu.resize(static_cast<Eigen::Index>(n));
    for (std::size_t a = 0; a < n; ++a) {
        const auto i = static_cast<Eigen::Index>(3 * a);
        out.q(i) = gap(rng);
        out.q(i + 1) = tangential(rng);
        out.q(i + 2) = tangential(rng);
        out.mu(static_cast<Eigen::Index>(a)) = frictionless ? 0.0 : friction(rng);
    }
    return out;
}

// ------------------------------------------------------------------------------------------------
// 1. Single contact, closed forms
// ------------------------------------------------------------------------------------------------

TEST(GaussSeidelContactBlockDiagonal,
     OneSweepSolvesIndependentContactsAndIgnoresOffDiagonalBlocks) {
    // Two contacts, W = diag blocks only, flagged block_diagonal, with garbage in the off-diagonal
    // blocks (never read). Each contact is then its own single-contact problem, solved in one
    // sweep: contact 0 sticks, f = -W^-1 q = (0.5, -0.1, 0.04) (W = diag(2, .5, .5),
    // q = (-1, .05, -.02)); contact 1 slips, f = (0.5, -0.15, 0.2) (q = (-1, .6, -.8), mu = .5).
    Problem p{};
    p.contact_count = 2;
    p.block_diagonal = true;
    for (std::size_t a = 0; a < 2; ++a)
        p.block(a, a) = {2.0, 0, 0, 0, 0.5, 0, 0, 0, 0.5};
    p.block(0, 1) = {7.0, 7.0, 7.0, 7.0, 7.0, 7.0, 7.0, 7.0, 7.0};
    p.block(1, 0) = {-3.0, 1.0, 2.0, 5.0, -4.0, 1.0, 9.0, 9.0, 9.0};
    p.free_displacement[0] = {-1.0, 0.05, -0.02};
    p.free_displacement[1] = {-1.0, 0.6, -0.8};
    p.friction[0] = 0.5;
    p.friction[1] = 0.5;
    Settings one_sweep = converge_to(0.0, 1);
    one_sweep.mode = sc::SweepMode::fixed;
    Forces f = zero_forces();
    const auto report = sc::solve_contacts(p, one_sweep, f);
    EXPECT_EQ(report.states[0], ContactState::sticking);
    EXPECT_EQ(report.states[1], ContactState::slipping);
    EXPECT_NEAR(f[0][0], 0.5, 1e-14);
    EXPECT_NEAR(f[0][1], -0.1, 1e-14);
    EXPECT_NEAR(f[0][2], 0.04, 1e-14);
    EXPECT_NEAR(f[1][0], 0.5, 1e-12);
    EXPECT_NEAR(f[1][1], -0.15, 1e-12);
    EXPECT_NEAR(f[1][2], 0.2, 1e-12);
    EXPECT_LE(report.residuals.complementarity, 1e-12);
    EXPECT_LE(report.residuals.friction, 1e-12);
}

TEST(GaussSeidelContactSingle, SeparationGivesZeroForce) {
    // delta_free_n = 0.2 mm > 0: the contact opens, f = 0 whatever the tangential motion.
    const Single s = solve_single(Eigen::Vector3d(2.0, 0.5, 0.5).asDiagonal().toDenseMatrix(),
                                  Eigen::Vector3d(0.2, 0.5, -0.3), 0.5);
    EXPECT_EQ(s.report.states[0], ContactState::separated);
    EXPECT_EQ(s.f[0][0], 0.0);
    EXPECT_EQ(s.f[0][1], 0.0);
    EXPECT_EQ(s.f[0][2], 0.0);
    EXPECT_EQ(s.report.status, sc::ContactSolveStatus::converged);
}

TEST(GaussSeidelContactSingle, StickIsMinusWInverseDeltaFree) {
    // W = diag(2, 0.5, 0.5), q = (-1, 0.05, -0.02), mu = 0.5:
    // f = -W^-1 q = (0.5, -0.1, 0.04); |f_T| = 0.1077 < mu f_n = 0.25 -> stick.
    const Single s = solve_single(Eigen::Vector3d(2.0, 0.5, 0.5).asDiagonal().toDenseMatrix(),
                                  Eigen::Vector3d(-1.0, 0.05, -0.02), 0.5);
    EXPECT_EQ(s.report.states[0], ContactState::sticking);
    EXPECT_NEAR(s.f[0][0], 0.5, 1e-14);
    EXPECT_NEAR(s.f[0][1], -0.1, 1e-14);
    EXPECT_NEAR(s.f[0][2], 0.04, 1e-14);
}

TEST(GaussSeidelContactSingle, SlipIsOnTheConeOppositeTheFreeTangentialMotion) {
    // W = diag(2, 0.5, 0.5), q = (-1, 0.6, -0.8), mu = 0.5: stick would need |f_T| = 2 > 0.25.
    // Slip: f_n = -q_n / w_n = 0.5, f_T = -mu f_n q_T / |q_T| = -0.25 (0.6, -0.8) = (-0.15, 0.2).
    const Single s = solve_single(Eigen::Vector3d(2.0, 0.5, 0.5).asDiagonal().toDenseMatrix(),
                                  Eigen::Vector3d(-1.0, 0.6, -0.8), 0.5);
    EXPECT_EQ(s.report.states[0], ContactState::slipping);
    EXPECT_NEAR(s.f[0][0], 0.5, 1e-14);
    EXPECT_NEAR(s.f[0][1], -0.15, 1e-14);
    EXPECT_NEAR(s.f[0][2], 0.2, 1e-14);
}

TEST(GaussSeidelContactSingle, IsotropicSlipNeedsOneLocalIteration) {
    // The closed-form start of the slip root-finder is exact for W_aa = diag(w_n, w_t, w_t).
    const sc::ContactBlock3<double> a{2.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.5};
    const auto local = sc::solve_local_contact(a, {-1.0, 0.6, -0.8}, 0.5, 60, false);
    EXPECT_EQ(local.state, ContactState::slipping);
    EXPECT_EQ(local.iterations, 1U);
}

TEST(GaussSeidelContactSingle, FrictionlessSlip) {
    // mu = 0: f = (-q_n / w_n, 0, 0) = (0.5, 0, 0).
    const Single s = solve_single(Eigen::Vector3d(2.0, 0.5, 0.5).asDiagonal().toDenseMatrix(),
                                  Eigen::Vector3d(-1.0, 0.01, 0.0), 0.0);
    EXPECT_EQ(s.report.states[0], ContactState::slipping);
    EXPECT_NEAR(s.f[0][0], 0.5, 1e-15);
    EXPECT_EQ(s.f[0][1], 0.0);
    EXPECT_EQ(s.f[0][2], 0.0);
}

TEST(GaussSeidelContactSingle, NonDiagonalBlockSlipHandChecked) {
    // W = [[2, 0.5, 0], [0.5, 1, 0], [0, 0, 1]], q = (-1, 0, 0), mu = 0.1.
    // Stick: f = W^-1 (1, 0, 0) = (1/1.75, -0.5/1.75, 0) = (0.571, -0.286, 0); 0.286 > 0.0571.
    // Slip along t (s decouples): f_t = sigma mu f_n.  delta_n = 2 f_n + 0.5 f_t - 1 = 0 gives
    // f_n = 1 / (2 + 0.05 sigma); delta_t = 0.5 f_n + f_t = f_n (0.5 + 0.1 sigma) > 0 for both
    // signs, so f_t must be negative: sigma = -1, f_n = 1/1.95, f_t = -0.1/1.95,
    // delta_t = 0.4/1.95 > 0 (opposite f_t, as Coulomb requires).
    Eigen::Matrix3d w;
    w << 2.0, 0.5, 0.0, 0.5, 1.0, 0.0, 0.0, 0.0, 1.0;
    const Single s = solve_single(w, Eigen::Vector3d(-1.0, 0.0, 0.0), 0.1);
    EXPECT_EQ(s.report.states[0], ContactState::slipping);
    EXPECT_NEAR(s.f[0][0], 1.0 / 1.95, 1e-12);
    EXPECT_NEAR(s.f[0][1], -0.1 / 1.95, 1e-12);
    EXPECT_NEAR(s.f[0][2], 0.0, 1e-15);
}

TEST(GaussSeidelContactSingle, AnisotropicTangentialBlockSlipHandChecked) {
    // W = diag(1, 1, 3), mu = 0.5, q = (-1, 0.6, 1.6).  f_n = 1.  With slip direction u and
    // delta_T = lambda u:  q_T = (lambda I + mu f_n diag(1, 3)) u.  lambda = 0.5, u = (0.6, 0.8)
    // gives q_T = (0.6 * 1.0, 0.8 * 2.0) = (0.6, 1.6): f_T = -0.5 u = (-0.3, -0.4),
    // delta = (0, 0.3, 0.4).  (Stick would need |(-0.6, -0.533)| = 0.80 > 0.5.)
    const Single s = solve_single(Eigen::Vector3d(1.0, 1.0, 3.0).asDiagonal().toDenseMatrix(),
                                  Eigen::Vector3d(-1.0, 0.6, 1.6), 0.5);
    EXPECT_EQ(s.report.states[0], ContactState::slipping);
    EXPECT_NEAR(s.f[0][0], 1.0, 1e-12);
    EXPECT_NEAR(s.f[0][1], -0.3, 1e-12);
    EXPECT_NEAR(s.f[0][2], -0.4, 1e-12);
}

TEST(GaussSeidelContactSingle, DegenerateBlockAndInvalidInputAreReported) {
    // W_nn = 0: contact is degenerate, f = 0.
    const Single s = solve_single(Eigen::Vector3d(0.0, 1.0, 1.0).asDiagonal().toDenseMatrix(),
                                  Eigen::Vector3d(-1.0, 0.0, 0.0), 0.3);
    EXPECT_EQ(s.report.states[0], ContactState::degenerate);
    EXPECT_EQ(s.report.degenerate_contacts, 1U);
    EXPECT_EQ(s.f[0][0], 0.0);

    // Negative mu and too many contacts: invalid input, forces untouched.
    auto p = make_problem(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-1.0, 0.0, 0.0),
                          Eigen::VectorXd::Constant(1, -0.1));
    Forces f = zero_forces();
    f[0] = {7.0, 0.0, 0.0};
    auto report = sc::solve_contacts(*p, converge_to(1e-9), f);
    EXPECT_EQ(report.status, sc::ContactSolveStatus::invalid_input);
    EXPECT_EQ(report.sweeps, 0U);
    EXPECT_EQ(f[0][0], 7.0);
    p->friction[0] = 0.1;
    p->contact_count = max_contacts + 1;
    report = sc::solve_contacts(*p, converge_to(1e-9), f);
    EXPECT_EQ(report.status, sc::ContactSolveStatus::invalid_input);
    EXPECT_EQ(f[0][0], 7.0);
}

// ------------------------------------------------------------------------------------------------
// 2 + 4. Random multi-contact problems: residuals, per-state conditions, dissipation
// ------------------------------------------------------------------------------------------------

TEST(GaussSeidelContactRandom, ThousandProblemsSatisfyTheContactLawsOfTheirStates) {
    std::mt19937_64 rng(20240611U);
    std::uniform_int_distribution<std::size_t> count(2, max_contacts);
    constexpr double solve_tolerance = 1e-10;  // N, change between sweeps
    constexpr double force_tol = 1e-9;         // N
    constexpr double disp_tol = 1e-9;          // mm (W ~ 1 mm/N)
    std::vector<std::size_t> sweeps_1e6;
    std::size_t counts[4] = {0, 0, 0, 0};
    double worst_residual = 0.0;
    for (int trial = 0; trial < 1000; ++trial) {
        const std::size_t n = count(rng);
        const RandomProblem rp = random_problem(rng, n, false);
        const auto p = make_problem(rp.w, rp.q, rp.mu);

        // Sweep count at the tolerance 1e-6 N (reported, not asserted).
        Forces f6 = zero_forces();
        const auto r6 = sc::solve_contacts(*p, converge_to(1e-6), f6);
        EXPECT_EQ(r6.status, sc::ContactSolveStatus::converged) << "trial " << trial;
        sweeps_1e6.push_back(r6.sweeps);

        Forces f = zero_forces();
        const auto report = sc::solve_contacts(*p, converge_to(solve_tolerance), f);
        ASSERT_EQ(report.status, sc::ContactSolveStatus::converged) << "trial " << trial;
        EXPECT_EQ(report.degenerate_contacts, 0U);
        EXPECT_LE(report.residuals.complementarity, force_tol) << "trial " << trial;
        EXPECT_LE(report.residuals.cone_violation, force_tol) << "trial " << trial;
        EXPECT_LE(report.residuals.friction, force_tol) << "trial " << trial;
        worst_residual = std::max({worst_residual, report.residuals.complementarity,
                                   report.residuals.cone_violation, report.residuals.friction});

        // Independent check of the conditions on delta = W f + q (Eigen).
        const Eigen::VectorXd fv = stacked(f, n);
        const Eigen::VectorXd delta = rp.w * fv + rp.q;
        for (std::size_t a = 0; a < n; ++a) {
            const auto i = static_cast<Eigen::Index>(3 * a);
            const double mu = rp.mu(static_cast<Eigen::Index>(a));
            const double f_n = fv(i);
            const Eigen::Vector2d f_t = fv.segment<2>(i + 1);
            const Eigen::Vector2d d_t = delta.segment<2>(i + 1);
            const double d_n = delta(i);
            // Always: f_n >= 0, delta_n >= 0, cone, and friction dissipates (test 4).
            EXPECT_GE(f_n, 0.0);
            EXPECT_GE(d_n, -disp_tol);
            EXPECT_LE(f_t.norm(), mu * f_n + force_tol);
            // Dissipation: f_T . delta_T <= 0 up to the displacement tolerance (in N mm).
            EXPECT_LE(f_t.dot(d_t), f_t.norm() * disp_tol) << "trial " << trial << " contact " << a;
            const ContactState state = report.states[a];
            counts[static_cast<int>(state)]++;
            switch (state) {
                case ContactState::separated:
                    EXPECT_EQ(f_n, 0.0);
                    EXPECT_EQ(f_t.norm(), 0.0);
                    break;
                case ContactState::sticking:
                    EXPECT_LE(std::abs(d_n), disp_tol);
                    EXPECT_LE(d_t.norm(), disp_tol) << "trial " << trial << " contact " << a;
                    break;
                case ContactState::slipping:
                    EXPECT_LE(std::abs(d_n), disp_tol);
                    EXPECT_NEAR(f_t.norm(), mu * f_n, force_tol);
                    // f_T antiparallel to delta_T: f_T |delta_T| + mu f_n delta_T = 0.
                    EXPECT_LE((f_t * d_t.norm() + mu * f_n * d_t).norm(), 1e-6)
                        << "trial " << trial << " contact " << a;
                    break;
                case ContactState::degenerate:
                    ADD_FAILURE() << "degenerate contact in a well-posed problem";
                    break;
            }
        }
    }
    std::sort(sweeps_1e6.begin(), sweeps_1e6.end());
    std::cout << "[ sweeps at 1e-6 N ] median " << sweeps_1e6[sweeps_1e6.size() / 2] << ", 90% "
              << sweeps_1e6[sweeps_1e6.size() * 9 / 10] << ", max " << sweeps_1e6.back()
              << "; states: separated " << counts[0] << ", sticking " << counts[1] << ", slipping "
              << counts[2] << "; worst residual at 1e-10 N: " << worst_residual << " N\n";
    // Every branch was exercised.
    EXPECT_GT(counts[0], 100U);
    EXPECT_GT(counts[1], 100U);
    EXPECT_GT(counts[2], 100U);
}

// ------------------------------------------------------------------------------------------------
// 3. Frictionless: compare with active-set enumeration
// ------------------------------------------------------------------------------------------------

// Solves the LCP 0 <= x ⟂ A x + b >= 0 (A SPD, size <= 6) by trying every active set.
Eigen::VectorXd enumerate_lcp(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, int& matches) {
    const Eigen::Index n = b.size();
    Eigen::VectorXd best = Eigen::VectorXd::Constant(n, -1.0);
    matches = 0;
    for (std::uint32_t mask = 0; mask < (1U << n); ++mask) {
        std::vector<Eigen::Index> act;
        for (Eigen::Index i = 0; i < n; ++i) {
            if ((mask >> i) & 1U) {
                act.push_back(i);
            }
        }
        const auto k = static_cast<Eigen::Index>(act.size());
        Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
        if (k > 0) {
            Eigen::MatrixXd aa(k, k);
            Eigen::VectorXd ba(k);
            for (Eigen::Index r = 0; r < k; ++r) {
                ba(r) = b(act[static_cast<std::size_t>(r)]);
                for (Eigen::Index c = 0; c < k; ++c) {
                    aa(r, c) =
                        a(act[static_cast<std::size_t>(r)], act[static_cast<std::size_t>(c)]);
                }
            }
            const Eigen::VectorXd xa = aa.ldlt().solve(-ba);
            for (Eigen::Index r = 0; r < k; ++r) {
                x(act[static_cast<std::size_t>(r)]) = xa(r);
            }
        }
        const Eigen::VectorXd w = a * x + b;
        bool ok = true;
        for (Eigen::Index i = 0; i < n; ++i) {
            const bool active = ((mask >> i) & 1U) != 0U;
            if (active ? x(i) < -1e-12 : w(i) < -1e-12) {
                ok = false;
            }
        }
        if (ok) {
            ++matches;
            best = x;
        }
    }
    return best;
}

TEST(GaussSeidelContactFrictionless, MatchesActiveSetEnumeration) {
    std::mt19937_64 rng(77U);
    std::uniform_int_distribution<std::size_t> count(1, 6);
    for (int trial = 0; trial < 300; ++trial) {
        const std::size_t n = count(rng);
        const RandomProblem rp = random_problem(rng, n, true);
        const auto p = make_problem(rp.w, rp.q, rp.mu);
        Forces f = zero_forces();
        const auto report = sc::solve_contacts(*p, converge_to(1e-12), f);
        ASSERT_EQ(report.status, sc::ContactSolveStatus::converged);

        // Normal-only LCP: W_nn (n x n, rows/cols 3a) and q_n.
        const auto nn = static_cast<Eigen::Index>(n);
        Eigen::MatrixXd wn(nn, nn);
        Eigen::VectorXd qn(nn);
        for (Eigen::Index a = 0; a < nn; ++a) {
            qn(a) = rp.q(3 * a);
            for (Eigen::Index b = 0; b < nn; ++b) {
                wn(a, b) = rp.w(3 * a, 3 * b);
            }
        }
        int matches = 0;
        const Eigen::VectorXd expected = enumerate_lcp(wn, qn, matches);
        ASSERT_GE(matches, 1) << "trial " << trial;  // unique for SPD (degenerate ties aside)
        for (std::size_t a = 0; a < n; ++a) {
            EXPECT_NEAR(f[a][0], expected(static_cast<Eigen::Index>(a)), 1e-9)
                << "trial " << trial << " contact " << a;
            EXPECT_EQ(f[a][1], 0.0);
            EXPECT_EQ(f[a][2], 0.0);
        }
    }
}

// ------------------------------------------------------------------------------------------------
// 5. Warm start and fixed-sweep mode
// ------------------------------------------------------------------------------------------------

TEST(GaussSeidelContactSweeps, WarmStartFromTheSolutionTakesOneSweep) {
    std::mt19937_64 rng(5U);
    for (int trial = 0; trial < 50; ++trial) {
        const RandomProblem rp = random_problem(rng, 12, false);
        const auto p = make_problem(rp.w, rp.q, rp.mu);
        Forces f = zero_forces();
        const auto cold = sc::solve_contacts(*p, converge_to(1e-9), f);
        ASSERT_EQ(cold.status, sc::ContactSolveStatus::converged);
        EXPECT_GT(cold.sweeps, 1U);
        const auto warm = sc::solve_contacts(*p, converge_to(1e-9), f);
        EXPECT_EQ(warm.status, sc::ContactSolveStatus::converged);
        EXPECT_EQ(warm.sweeps, 1U) << "trial " << trial;
    }
}

TEST(GaussSeidelContactSweeps, FixedModeDoesExactlyTheRequestedSweeps) {
    std::mt19937_64 rng(6U);
    const RandomProblem rp = random_problem(rng, 10, false);
    const auto p = make_problem(rp.w, rp.q, rp.mu);
    Settings fixed{};
    fixed.mode = sc::SweepMode::fixed;
    fixed.tolerance = 1.0;  // would stop at once in until_converged mode
    fixed.local_iterations = 30;
    for (std::size_t sweeps : {std::size_t{1}, std::size_t{7}, std::size_t{40}}) {
        fixed.max_sweeps = sweeps;
        Forces f = zero_forces();
        const auto report = sc::solve_contacts(*p, fixed, f);
        EXPECT_EQ(report.status, sc::ContactSolveStatus::fixed_sweeps_done);
        EXPECT_EQ(report.sweeps, sweeps);
        // Again from the converged solution: still exactly that many sweeps.
        const auto again = sc::solve_contacts(*p, fixed, f);
        EXPECT_EQ(again.sweeps, sweeps);
    }
    // Fixed mode and until_converged agree once enough sweeps are done.
    fixed.max_sweeps = 2000;
    Forces f_fixed = zero_forces();
    sc::solve_contacts(*p, fixed, f_fixed);
    Forces f_conv = zero_forces();
    sc::solve_contacts(*p, converge_to(1e-13), f_conv);
    for (std::size_t a = 0; a < 10; ++a) {
        for (std::size_t k = 0; k < 3; ++k) {
            EXPECT_NEAR(f_fixed[a][k], f_conv[a][k], 1e-9);
        }
    }
}

}  // namespace
