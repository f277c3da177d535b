#pragma once
// A wire node's rest point in a moving lumen (the rod living in the world, issue #33): the point
// r of the lumen's rest frame that the vessels' motion carries to the node's world position x,
//   x = r + d(r, a)        (d: LumenMotion at a fraction a of the step)
// found by fixed-point steps r <- x - d(r, a) from a guess. The inverse is not unique where a
// vessel's motion ends: the vessel skin carries a rest point by the centerline points within its
// blend radius (4 mm) and leaves one beyond them all standing, so where a vessel has moved
// further than that radius the node's world position is itself a fixed point (d = 0 there) as
// well as the true rest point inside the vessel. Measured in the default beating scene with the
// wall in the solve: the tip just out of the catheter (whose guess, the aortic root's, is no
// motion) kept a zero offset while its neighbour's was 2-8 mm. The wire is continuous, so its
// neighbour's offset finds the node's vessel where its own guess does not.
#include <Eigen/Core>

#include "physics/guidewire/lumen_query.h"

namespace pcisim::physics {

// x = r + d(r, a) by at most kRestPointSteps fixed-point steps from the guess r, stopping once a
// step moves r less than 1 um
Eigen::Vector3d rest_point_from(const LumenMotion& motion, const Eigen::Vector3d& x_m, Eigen::Vector3d r_m, double a);

// a node's rest point from its own last offset (x - offset as the guess); where that answer is
// not carried by the motion (LumenMotion::carries: some vessel's motion reaches it, which is not
// the same as lying in its lumen: the skin's blend reaches 4 mm from a centerline), or its offset
// lies further than kRestPointJumpM from the offset of the neighbour nearer the hub (null: none,
// and the first answer stands), the fixed point from the neighbour's offset too. Of the two: one
// with x = r + d(r) within 10 um before one without; then a carried one before one that is not
// (where nothing reaches, every world position is its own fixed point: a node in the wide aortic
// root is legitimately there, a node in a coronary is not); then the one whose offset is nearer
// the neighbour's. Costs one more fixed-point search where the first answer is doubted (at the
// LM's ostium, where neighbouring offsets differ by millimetres, every step)
Eigen::Vector3d wire_node_rest_point(const LumenMotion& motion, const Eigen::Vector3d& x_m,
                                     const Eigen::Vector3d& own_offset_m, const Eigen::Vector3d* neighbour_offset_m,
                                     double a);

inline constexpr int kRestPointSteps = 8;
inline constexpr double kRestPointJumpM = 0.5e-3;

}  // namespace pcisim::physics
