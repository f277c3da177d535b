// The chain solver against a dense Cholesky solve of the same matrix, and its refusal of a
// singular pivot.
#include "physics/rod/block_tridiagonal.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace pcisim::physics::rod {
namespace {

// a random symmetric positive definite chain and its dense matrix: diagonally dominant blocks
// scaled over `decades` decades (10^(j % decades)), as a rod's are
void fill_random_chain(std::mt19937& rng, int decades, BlockTridiagonal6* chain, Eigen::MatrixXd* dense) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = chain->units();
  *dense = Eigen::MatrixXd::Zero(6 * n, 6 * n);
  for (int j = 0; j < n; ++j) {
    BlockTridiagonal6::Block m;
    for (int k = 0; k < 36; ++k) m(k) = u(rng);
    const double scale = std::pow(10.0, j % decades);
    chain->diagonal(j) = scale * (m * m.transpose() + 20.0 * BlockTridiagonal6::Block::Identity());
    dense->block<6, 6>(6 * j, 6 * j) = chain->diagonal(j);
    if (j + 1 < n) {
      for (int k = 0; k < 36; ++k) m(k) = u(rng);
      chain->upper(j) = std::sqrt(scale) * m;
      dense->block<6, 6>(6 * j, 6 * j + 6) = chain->upper(j);
      dense->block<6, 6>(6 * j + 6, 6 * j) = chain->upper(j).transpose();
    }
  }
}

TEST(BlockTridiagonal6, SolvesARandomSpdChainAsADenseSolveDoes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 9;
  BlockTridiagonal6 chain(n);
  Eigen::MatrixXd dense;
  fill_random_chain(rng, 5, &chain, &dense);
  std::vector<BlockTridiagonal6::Vector> b(n), x(n);
  Eigen::VectorXd bd(6 * n);
  for (int j = 0; j < n; ++j) {
    for (int k = 0; k < 6; ++k) b[j](k) = u(rng);
    bd.segment<6>(6 * j) = b[j];
  }
  ASSERT_TRUE(chain.factor());
  chain.solve(b, &x);
  const Eigen::VectorXd xd = dense.llt().solve(bd);
  for (int j = 0; j < n; ++j) EXPECT_LT((x[j] - xd.segment<6>(6 * j)).norm(), 1e-12 * xd.norm()) << "unit " << j;
  // and the residual of the dense matrix with the chain's answer
  Eigen::VectorXd xc(6 * n);
  for (int j = 0; j < n; ++j) xc.segment<6>(6 * j) = x[j];
  EXPECT_LT((dense * xc - bd).norm(), 1e-10 * bd.norm());
}

TEST(BlockTridiagonal6, SolvesTheTailFromAFirstUnit) {
  // units before `first` are neither read nor written: garbage there changes nothing
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 7, first = 3;
  BlockTridiagonal6 chain(n);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(6 * (n - first), 6 * (n - first));
  for (int j = 0; j < n; ++j) {
    BlockTridiagonal6::Block m;
    for (int k = 0; k < 36; ++k) m(k) = u(rng);
    chain.diagonal(j) = j < first
                            ? BlockTridiagonal6::Block::Constant(std::nan(""))
                            : BlockTridiagonal6::Block(m * m.transpose() + 10.0 * BlockTridiagonal6::Block::Identity());
    if (j >= first) dense.block<6, 6>(6 * (j - first), 6 * (j - first)) = chain.diagonal(j);
    if (j + 1 < n) {
      for (int k = 0; k < 36; ++k) m(k) = u(rng);
      chain.upper(j) = j < first ? BlockTridiagonal6::Block::Constant(std::nan("")) : m;
      if (j >= first) {
        dense.block<6, 6>(6 * (j - first), 6 * (j - first) + 6) = m;
        dense.block<6, 6>(6 * (j - first) + 6, 6 * (j - first)) = m.transpose();
      }
    }
  }
  std::vector<BlockTridiagonal6::Vector> b(n, BlockTridiagonal6::Vector::Constant(std::nan(""))), x(n);
  Eigen::VectorXd bd(6 * (n - first));
  for (int j = first; j < n; ++j) {
    for (int k = 0; k < 6; ++k) b[j](k) = u(rng);
    bd.segment<6>(6 * (j - first)) = b[j];
  }
  ASSERT_TRUE(chain.factor(first));
  chain.solve(b, &x, first);
  const Eigen::VectorXd xd = dense.llt().solve(bd);
  for (int j = first; j < n; ++j) EXPECT_LT((x[j] - xd.segment<6>(6 * (j - first))).norm(), 1e-12 * xd.norm()) << j;
}

TEST(BlockTridiagonal6, APartialSolveGivesTheDenseSolvesUnitsAtAndBelowWhatIsWanted) {
  // b zero before unit 5 (garbage there must not be read), x wanted from unit 3 on: the
  // answer there is the dense solve's, and units below 3 are left as they were
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 10, nonzero_from = 5, lowest = 3;
  BlockTridiagonal6 chain(n);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(6 * n, 6 * n);
  for (int j = 0; j < n; ++j) {
    BlockTridiagonal6::Block m;
    for (int k = 0; k < 36; ++k) m(k) = u(rng);
    chain.diagonal(j) = m * m.transpose() + 15.0 * BlockTridiagonal6::Block::Identity();
    dense.block<6, 6>(6 * j, 6 * j) = chain.diagonal(j);
    if (j + 1 < n) {
      for (int k = 0; k < 36; ++k) m(k) = u(rng);
      chain.upper(j) = m;
      dense.block<6, 6>(6 * j, 6 * j + 6) = m;
      dense.block<6, 6>(6 * j + 6, 6 * j) = m.transpose();
    }
  }
  std::vector<BlockTridiagonal6::Vector> b(n, BlockTridiagonal6::Vector::Constant(std::nan("")));
  std::vector<BlockTridiagonal6::Vector> x(n, BlockTridiagonal6::Vector::Constant(42.0));
  Eigen::VectorXd bd = Eigen::VectorXd::Zero(6 * n);
  for (int j = nonzero_from; j < n; ++j) {
    for (int k = 0; k < 6; ++k) b[j](k) = u(rng);
    bd.segment<6>(6 * j) = b[j];
  }
  ASSERT_TRUE(chain.factor());
  chain.solve_partial(b, &x, nonzero_from, lowest);
  const Eigen::VectorXd xd = dense.llt().solve(bd);
  for (int j = lowest; j < n; ++j) EXPECT_LT((x[j] - xd.segment<6>(6 * j)).norm(), 1e-12 * xd.norm()) << "unit " << j;
  for (int j = 0; j < lowest; ++j) EXPECT_EQ(x[j](0), 42.0) << "unit " << j << " was written";
}

TEST(BlockTridiagonal6, ThreeRightHandSidesAtOnceAreThreeDenseSolves) {
  // the contact compliance's form: a node's three axes, b zero before unit 4, x wanted from 4 on
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 8, from = 4;
  BlockTridiagonal6 chain(n);
  Eigen::MatrixXd dense;
  fill_random_chain(rng, 4, &chain, &dense);
  std::vector<BlockTridiagonal6::Columns3> b(n, BlockTridiagonal6::Columns3::Constant(std::nan("")));
  std::vector<BlockTridiagonal6::Columns3> x(n, BlockTridiagonal6::Columns3::Zero());
  Eigen::MatrixXd bd = Eigen::MatrixXd::Zero(6 * n, 3);
  for (int j = from; j < n; ++j) {
    for (int k = 0; k < 18; ++k) b[j](k) = u(rng);
    bd.middleRows<6>(6 * j) = b[j];
  }
  ASSERT_TRUE(chain.factor());
  chain.solve_partial(b, &x, from, from);
  const Eigen::MatrixXd xd = dense.llt().solve(bd);
  for (int j = from; j < n; ++j) EXPECT_LT((x[j] - xd.middleRows<6>(6 * j)).norm(), 1e-12 * xd.norm()) << "unit " << j;
}

TEST(BlockTridiagonal6, RefusesASingularPivot) {
  BlockTridiagonal6 chain(3);
  for (int j = 0; j < 3; ++j) chain.diagonal(j) = BlockTridiagonal6::Block::Identity();
  chain.diagonal(1)(4, 4) = 0.0;  // a constraint that nothing can move
  EXPECT_FALSE(chain.factor());
  chain.diagonal(1)(4, 4) = std::nan("");
  EXPECT_FALSE(chain.factor());
}

}  // namespace
}  // namespace pcisim::physics::rod
