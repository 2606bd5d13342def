// Block-tridiagonal storage and solver (model/linalg/block_tridiagonal.hpp) against dense
// Eigen: to_dense / multiply / column / constrain_dof / add_element / add_scaled, and the
// solver against PartialPivLU on the dense matrix.
#include <gtest/gtest.h>

#include <cmath>

#include "model/linalg/block_tridiagonal.hpp"
#include "model_test_support.hpp"

namespace scopekin::model {
namespace {

using testing::matrices_near;
using testing::Random;

Mat6 random_block(Random& rng, double lo, double hi) {
    Mat6 b;
    for (int i = 0; i < 36; ++i)
        b(i / 6, i % 6) = rng.uniform(lo, hi);
    return b;
}

Eigen::VectorXd random_vector(Random& rng, std::size_t n) {
    Eigen::VectorXd v(static_cast<Eigen::Index>(n));
    for (Eigen::Index i = 0; i < v.size(); ++i)
        v(i) = rng.uniform(-1, 1);
    return v;
}

/// Nonsymmetric, block diagonally dominant: off-diagonal entries in [-1, 1], diagonal blocks
/// with |a_ii| >= 20 > sum of the 18 off-diagonal entries of the row (so no pivoting is needed
/// between blocks and the system is well conditioned).
BlockTridiagonalMatrix random_dominant(Random& rng, std::size_t blocks) {
    BlockTridiagonalMatrix a(blocks);
    for (std::size_t i = 0; i < blocks; ++i) {
        a.diagonal(i) = random_block(rng, -1, 1);
        for (int k = 0; k < 6; ++k)
            a.diagonal(i)(k, k) = (rng.uniform(0, 1) < 0.5 ? -1.0 : 1.0) * rng.uniform(20, 40);
        if (i + 1 < blocks) {
            a.upper(i) = random_block(rng, -1, 1);
            a.lower(i) = random_block(rng, -1, 1);
        }
    }
    return a;
}

TEST(BlockTridiagonal, ToDensePlacesBlocksOnTheThreeBlockDiagonals) {
    BlockTridiagonalMatrix a(3);
    a.diagonal(0).setConstant(1);
    a.diagonal(1).setConstant(2);
    a.diagonal(2).setConstant(3);
    a.upper(0).setConstant(4);
    a.upper(1).setConstant(5);
    a.lower(0).setConstant(6);
    a.lower(1).setConstant(7);
    Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(18, 18);
    expected.block(0, 0, 6, 6).setConstant(1);
    expected.block(6, 6, 6, 6).setConstant(2);
    expected.block(12, 12, 6, 6).setConstant(3);
    expected.block(0, 6, 6, 6).setConstant(4);   // (0, 1)
    expected.block(6, 12, 6, 6).setConstant(5);  // (1, 2)
    expected.block(6, 0, 6, 6).setConstant(6);   // (1, 0)
    expected.block(12, 6, 6, 6).setConstant(7);  // (2, 1)
    EXPECT_TRUE(matrices_near(a.to_dense(), expected, 0.0));
    EXPECT_EQ(a.size(), 18u);
    EXPECT_EQ(a.block_count(), 3u);
}

TEST(BlockTridiagonal, MultiplyEqualsDenseProduct) {
    Random rng(31);
    for (std::size_t blocks : {1u, 2u, 7u, 30u}) {
        const BlockTridiagonalMatrix a = random_dominant(rng, blocks);
        const Eigen::VectorXd x = random_vector(rng, 6 * blocks);
        EXPECT_TRUE(matrices_near(a.multiply(x), a.to_dense() * x, 1e-12)) << blocks << " blocks";
    }
}

TEST(BlockTridiagonal, SolveMatchesDensePartialPivLU) {
    Random rng(32);
    for (std::size_t blocks : {1u, 2u, 10u, 23u, 50u}) {
        const BlockTridiagonalMatrix a = random_dominant(rng, blocks);
        const Eigen::VectorXd b = random_vector(rng, 6 * blocks);
        BlockTridiagonalSolver solver;
        ASSERT_TRUE(solver.factorize(a)) << blocks << " blocks";
        const Eigen::VectorXd x = solver.solve(b);
        const Eigen::VectorXd reference = a.to_dense().partialPivLu().solve(b);
        EXPECT_TRUE(matrices_near(x, reference, 1e-13)) << blocks << " blocks";
        EXPECT_LT((a.to_dense() * x - b).cwiseAbs().maxCoeff(), 1e-13) << blocks << " blocks";
    }
}

// A symmetric positive definite chain with large and small scales mixed in each block, like a
// beam's stiffness (N/mm against N mm/rad, ratios ~1e4): the 1D Laplacian kron a 6x6 SPD block.
TEST(BlockTridiagonal, SolvesABadlyScaledSymmetricPositiveDefiniteChain) {
    Random rng(33);
    const std::size_t blocks = 40;
    Mat6 c = random_block(rng, -1, 1);
    Mat6 spd = c * c.transpose() + Mat6::Identity();
    const Eigen::Matrix<double, 6, 1> scale =
        (Eigen::Matrix<double, 6, 1>() << 1, 1, 1, 100, 100, 100).finished();
    spd = scale.asDiagonal() * spd * scale.asDiagonal();
    BlockTridiagonalMatrix a(blocks);
    for (std::size_t i = 0; i < blocks; ++i) {
        a.diagonal(i) = 2.0 * spd + 1e-3 * Mat6::Identity();
        if (i + 1 < blocks) a.upper(i) = a.lower(i) = -spd;
    }
    const Eigen::VectorXd b = random_vector(rng, 6 * blocks);
    BlockTridiagonalSolver solver;
    ASSERT_TRUE(solver.factorize(a));
    const Eigen::VectorXd x = solver.solve(b);
    const Eigen::VectorXd reference = a.to_dense().partialPivLu().solve(b);
    EXPECT_LT((x - reference).norm(), 1e-8 * reference.norm());
}

// constrain_dof(d): row d and column d of the dense matrix replaced by e_d (identity row/column).
TEST(BlockTridiagonal, ConstrainDofReplacesRowAndColumnByIdentity) {
    Random rng(34);
    for (std::size_t dof : {0u, 5u, 6u, 14u, 29u}) {
        BlockTridiagonalMatrix a = random_dominant(rng, 5);
        Eigen::MatrixXd expected = a.to_dense();
        const auto d = static_cast<Eigen::Index>(dof);
        expected.row(d).setZero();
        expected.col(d).setZero();
        expected(d, d) = 1.0;
        a.constrain_dof(dof);
        EXPECT_TRUE(matrices_near(a.to_dense(), expected, 0.0)) << "dof " << dof;
    }
}

TEST(BlockTridiagonal, ColumnEqualsTheDenseColumn) {
    Random rng(35);
    const BlockTridiagonalMatrix a = random_dominant(rng, 4);
    const Eigen::MatrixXd dense = a.to_dense();
    for (std::size_t dof = 0; dof < a.size(); ++dof)
        EXPECT_TRUE(matrices_near(a.column(dof), dense.col(static_cast<Eigen::Index>(dof)), 0.0))
            << "dof " << dof;
}

// Constrained solve, as the Newton solvers use it: move the prescribed value to the right-hand
// side, constrain, solve. The result must equal a dense solve of the reduced (free) system.
TEST(BlockTridiagonal, ConstrainedSolveEqualsTheReducedDenseSolve) {
    Random rng(36);
    BlockTridiagonalMatrix a = random_dominant(rng, 6);
    const Eigen::MatrixXd dense = a.to_dense();
    Eigen::VectorXd r = random_vector(rng, a.size());
    const std::size_t fixed = 13;
    const double value = 0.7;
    Eigen::VectorXd rhs = r - a.column(fixed) * value;
    a.constrain_dof(fixed);
    rhs(static_cast<Eigen::Index>(fixed)) = value;
    BlockTridiagonalSolver solver;
    ASSERT_TRUE(solver.factorize(a));
    const Eigen::VectorXd x = solver.solve(rhs);
    EXPECT_DOUBLE_EQ(x(13), value);
    // Reference: rows != 13 of dense * x = r, with x_13 = value.
    Eigen::VectorXd residual = dense * x - r;
    residual(13) = 0.0;
    EXPECT_LT(residual.cwiseAbs().maxCoeff(), 1e-13);
}

TEST(BlockTridiagonal, AddElementAndAddScaledMatchDenseAssembly) {
    Random rng(37);
    const std::size_t nodes = 5;
    BlockTridiagonalMatrix a(nodes);
    Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(30, 30);
    for (std::size_t e = 0; e + 1 < nodes; ++e) {
        Eigen::Matrix<double, 12, 12> k;
        for (int i = 0; i < 144; ++i)
            k(i / 12, i % 12) = rng.uniform(-1, 1);
        a.add_element(e, k);
        expected.block(static_cast<Eigen::Index>(6 * e), static_cast<Eigen::Index>(6 * e), 12,
                       12) += k;
    }
    EXPECT_TRUE(matrices_near(a.to_dense(), expected, 1e-15));
    const BlockTridiagonalMatrix b = random_dominant(rng, nodes);
    const Eigen::MatrixXd b_dense = b.to_dense();
    a.add_scaled(b, -2.5);
    EXPECT_TRUE(matrices_near(a.to_dense(), expected - 2.5 * b_dense, 1e-14));
    a.set_zero();
    EXPECT_EQ(a.to_dense().cwiseAbs().maxCoeff(), 0.0);
}

TEST(BlockTridiagonal, SingularMatricesAreRejected) {
    Random rng(38);
    BlockTridiagonalSolver solver;
    // An all-zero diagonal block with zero coupling: the matrix has 6 zero rows.
    BlockTridiagonalMatrix zero_block = random_dominant(rng, 8);
    zero_block.diagonal(3).setZero();
    zero_block.upper(3).setZero();
    zero_block.lower(2).setZero();
    EXPECT_FALSE(solver.factorize(zero_block));
    // The all-zero matrix.
    EXPECT_FALSE(solver.factorize(BlockTridiagonalMatrix(5)));
    // Singular only through the coupling: a free-free chain of springs, [1 -1; -1 1] kron I_6
    // summed over elements (rigid translation in its null space); singular in the last pivot.
    BlockTridiagonalMatrix chain(6);
    Eigen::Matrix<double, 12, 12> spring = Eigen::Matrix<double, 12, 12>::Identity();
    spring.block<6, 6>(0, 6) = spring.block<6, 6>(6, 0) = -Mat6::Identity();
    for (std::size_t e = 0; e < 5; ++e)
        chain.add_element(e, spring);
    EXPECT_FALSE(solver.factorize(chain));
    // A NaN entry: either factorize() refuses it or the solution is visibly not finite (the
    // header promises no silent finite answer; solve_constrained() checks allFinite()).
    BlockTridiagonalMatrix nan = random_dominant(rng, 3);
    nan.diagonal(1)(2, 2) = std::nan("");
    EXPECT_TRUE(!solver.factorize(nan) ||
                !solver.solve(random_vector(rng, nan.size())).allFinite());
}

}  // namespace
}  // namespace scopekin::model
