#include "physics/guidewire/rest_point.h"

namespace pcisim::physics {
namespace {

// a step moving the rest point less than this: settled
constexpr double kSettledM = 1e-6;
// x = r + d(r) within this: r is a rest point of x
constexpr double kFixedM = 10e-6;

}  // namespace

Eigen::Vector3d rest_point_from(const LumenMotion& motion, const Eigen::Vector3d& x, Eigen::Vector3d r, double a) {
  for (int k = 0; k < kRestPointSteps; ++k) {
    const Eigen::Vector3d next = x - motion.displacement_m(r, a);
    const bool settled = (next - r).squaredNorm() < kSettledM * kSettledM;
    r = next;
    if (settled) break;
  }
  return r;
}

Eigen::Vector3d wire_node_rest_point(const LumenMotion& motion, const Eigen::Vector3d& x,
                                     const Eigen::Vector3d& own_offset, const Eigen::Vector3d* neighbour_offset,
                                     double a) {
  const Eigen::Vector3d r = rest_point_from(motion, x, x - own_offset, a);
  if (!neighbour_offset) return r;
  // x - r: the offset the answer gives the node
  const double off = ((x - r) - *neighbour_offset).norm();
  const bool carried = motion.carries(r);
  if (carried && !(off > kRestPointJumpM)) return r;
  const Eigen::Vector3d other = rest_point_from(motion, x, x - *neighbour_offset, a);
  // a fixed point before one that is not (the steps may stop short, or cycle where the field
  // folds); then one the motion carries before one it does not (a point no vessel's motion
  // reaches stands still by default, not because its vessel does); then the one nearer the
  // neighbour's offset (two vessels' reach: continuity along the wire)
  const auto fixed = [&](const Eigen::Vector3d& p) { return (x - p - motion.displacement_m(p, a)).norm() < kFixedM; };
  const bool own_fixed = fixed(r), other_fixed = fixed(other);
  if (own_fixed != other_fixed) return own_fixed ? r : other;
  const bool other_carried = motion.carries(other);
  if (carried != other_carried) return carried ? r : other;
  return ((x - other) - *neighbour_offset).norm() < off ? other : r;
}

}  // namespace pcisim::physics
