#pragma once
// A symmetric positive definite block-tridiagonal system with 6 x 6 blocks, solved by block
// Gaussian elimination along the chain (the block Thomas algorithm) in O(n): the linear solve of
// a rod's constraints, whose graph is a chain (Deul et al. 2018, "Direct position-based solver
// for stiff rods", solve a tree the same way). Sized once; factor() and solve() allocate nothing.
//   | D0  U0            |
//   | U0' D1  U1        |   D_j symmetric, U_j couples unit j (rows) with unit j + 1 (columns)
//   |     U1' D2  ...   |
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <vector>

namespace pcisim::physics::rod {

class BlockTridiagonal6 {
 public:
  using Block = Eigen::Matrix<double, 6, 6>;
  using Vector = Eigen::Matrix<double, 6, 1>;

  explicit BlockTridiagonal6(int units);

  int units() const { return static_cast<int>(diagonal_.size()); }
  Block& diagonal(int j) { return diagonal_[j]; }
  Block& upper(int j) { return upper_[j]; }  // j in [0, units - 1)

  // eliminates down the chain: S_0 = D_0, S_j = D_j - U_{j-1}' S_{j-1}^-1 U_{j-1}. False when a
  // pivot block is not positive definite (a NaN, or a constraint with no mobile body).
  // Only units [first, units) take part (the ones before are not solved, their entries unread).
  bool factor(int first = 0);
  // x = A^-1 b (after factor(first)) over units [first, units); b and x hold units() 6-vectors
  void solve(const std::vector<Vector>& b, std::vector<Vector>* x, int first = 0);

 private:
  std::vector<Block> diagonal_, upper_;
  std::vector<Eigen::LLT<Block>> pivot_;  // Cholesky of S_j
  std::vector<Block> reduced_upper_;      // X_j = S_j^-1 U_j
  std::vector<Vector> forward_;           // S_j^-1 y_j
};

}  // namespace pcisim::physics::rod
