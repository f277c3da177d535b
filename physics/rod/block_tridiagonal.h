#pragma once
// A symmetric positive definite block-tridiagonal system with N x N blocks, solved by block
// Gaussian elimination along the chain (the block Thomas algorithm) in O(n): the linear solve of
// a rod's constraints, whose graph is a chain (Deul et al. 2018, "Direct position-based solver
// for stiff rods", solve a tree the same way). Sized once; factor() and solve() allocate nothing.
//   | D0  U0            |
//   | U0' D1  U1        |   D_j symmetric, U_j couples unit j (rows) with unit j + 1 (columns)
//   |     U1' D2  ...   |
#include <algorithm>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <vector>

namespace pcisim::physics::rod {

template <int N>
class BlockTridiagonal {
 public:
  using Block = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;
  using Columns3 = Eigen::Matrix<double, N, 3>;

  explicit BlockTridiagonal(int units)
      : diagonal_(units, Block::Zero()),
        upper_(units > 0 ? units - 1 : 0, Block::Zero()),
        pivot_(units),
        pivot_inverse_(units, Block::Zero()),
        inverse_from_(units),
        reduced_upper_(units > 0 ? units - 1 : 0, Block::Zero()),
        forward_(units, Vector::Zero()),
        forward3_(units, Columns3::Zero()) {}

  int units() const { return static_cast<int>(diagonal_.size()); }
  Block& diagonal(int j) { return diagonal_[j]; }
  Block& upper(int j) { return upper_[j]; }  // j in [0, units - 1)

  // eliminates down the chain: S_0 = D_0, S_j = D_j - U_{j-1}' S_{j-1}^-1 U_{j-1}. False when a
  // pivot block is not positive definite (a NaN, or a constraint with no mobile body).
  // Only units [first, units) take part (the ones before are not solved, their entries unread).
  bool factor(int first = 0) {
    const int n = units();
    inverse_from_ = n;  // none of the pivots' inverses (made when a three-column solve needs them)
    for (int j = first; j < n; ++j) {
      Block s = diagonal_[j];
      if (j > first) s.noalias() -= upper_[j - 1].transpose() * reduced_upper_[j - 1];
      if (!s.allFinite()) return false;  // Eigen's Cholesky passes a NaN pivot
      pivot_[j].compute(s);
      if (pivot_[j].info() != Eigen::Success) return false;
      if (j + 1 < n) reduced_upper_[j] = pivot_[j].solve(upper_[j]);
    }
    return true;
  }

  // x = A^-1 b (after factor(first)) over units [first, units); b and x hold units() vectors
  void solve(const std::vector<Vector>& b, std::vector<Vector>* x, int first = 0) { solve_partial(b, x, first, first); }

  // the solve for a b that is zero before unit `nonzero_from`, and only units [lowest_wanted,
  // units) of x wanted (solve() is nonzero_from = lowest_wanted = first): the forward sweep starts at nonzero_from (the
  // units before it stay zero) and the back sweep stops at lowest_wanted, so a column of A^-1 whose b sits near the
  // chain's end costs what is left of the chain. Both in [first, units).
  void solve_partial(const std::vector<Vector>& b, std::vector<Vector>* x, int nonzero_from, int lowest_wanted) {
    const int n = units();
    if (nonzero_from >= n || lowest_wanted >= n) return;
    for (int j = nonzero_from; j < n; ++j) {
      Vector y = b[j];
      if (j > nonzero_from) y.noalias() -= upper_[j - 1].transpose() * forward_[j - 1];
      forward_[j] = pivot_[j].solve(y);
    }
    back_substitute(forward_, x, nonzero_from, lowest_wanted);
  }

  // the same for three right-hand sides at once (a node's three axes: the contact compliance's
  // columns, 3 per contact node per substep). These use the pivots' inverses, made for the units
  // they reach the first time after a factor(): a solve is then a product (the 6 x 6 triangular
  // solves took 40 % of a rod in contact's time, issue #33's dead end); one solve per factor, as
  // the rod's own iterations do, would not repay making them
  void solve_partial(const std::vector<Columns3>& b, std::vector<Columns3>* x, int nonzero_from, int lowest_wanted) {
    const int n = units();
    if (nonzero_from >= n || lowest_wanted >= n) return;
    for (int j = nonzero_from; j < inverse_from_; ++j) pivot_inverse_[j] = pivot_[j].solve(Block::Identity());
    inverse_from_ = std::min(inverse_from_, nonzero_from);
    for (int j = nonzero_from; j < n; ++j) {
      Columns3 y = b[j];
      if (j > nonzero_from) y.noalias() -= upper_[j - 1].transpose() * forward3_[j - 1];
      forward3_[j].noalias() = pivot_inverse_[j] * y;
    }
    back_substitute(forward3_, x, nonzero_from, lowest_wanted);
  }

 private:
  template <typename Rhs>
  void back_substitute(const std::vector<Rhs>& forward, std::vector<Rhs>* x, int nonzero_from,
                       int lowest_wanted) const {
    const int n = units();
    std::vector<Rhs>& out = *x;
    out[n - 1] = forward[n - 1];
    for (int j = n - 2; j >= lowest_wanted; --j) {
      out[j] = -(reduced_upper_[j] * out[j + 1]);
      if (j >= nonzero_from) out[j] += forward[j];
    }
  }

  std::vector<Block> diagonal_, upper_;
  std::vector<Eigen::LLT<Block>> pivot_;  // Cholesky of S_j (it says whether S_j is positive definite)
  std::vector<Block> pivot_inverse_;      // S_j^-1 for units [inverse_from_, units)
  int inverse_from_;
  std::vector<Block> reduced_upper_;  // X_j = S_j^-1 U_j
  std::vector<Vector> forward_;       // S_j^-1 y_j
  std::vector<Columns3> forward3_;    // (for three at once)
};

using BlockTridiagonal6 = BlockTridiagonal<6>;

}  // namespace pcisim::physics::rod
