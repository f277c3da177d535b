#include "physics/rod/block_tridiagonal.h"

namespace pcisim::physics::rod {

BlockTridiagonal6::BlockTridiagonal6(int units)
    : diagonal_(units, Block::Zero()),
      upper_(units > 0 ? units - 1 : 0, Block::Zero()),
      pivot_(units),
      reduced_upper_(units > 0 ? units - 1 : 0, Block::Zero()),
      forward_(units, Vector::Zero()) {}

bool BlockTridiagonal6::factor(int first) {
  const int n = units();
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

void BlockTridiagonal6::solve(const std::vector<Vector>& b, std::vector<Vector>* x, int first) {
  const int n = units();
  if (first >= n) return;
  // forward: y_j = b_j - U_{j-1}' S_{j-1}^-1 y_{j-1}, kept as z_j = S_j^-1 y_j
  for (int j = first; j < n; ++j) {
    Vector y = b[j];
    if (j > first) y.noalias() -= upper_[j - 1].transpose() * forward_[j - 1];
    forward_[j] = pivot_[j].solve(y);
  }
  // back: x_j = z_j - X_j x_{j+1}
  std::vector<Vector>& out = *x;
  out[n - 1] = forward_[n - 1];
  for (int j = n - 2; j >= first; --j) out[j] = forward_[j] - reduced_upper_[j] * out[j + 1];
}

}  // namespace pcisim::physics::rod
