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
// not carried by the motion (LumenMotion::carries), or its offset lies further than
// kRestPointJumpM from the offset of the neighbour nearer the hub (null: none, and the first
// answer stands), the fixed point from the neighbour's offset too. Of the two: a carried one
// before one that is not (nothing moves a point no vessel reaches, so it is a fixed point of
// every world position there: a node in the wide aortic root is one, a node in a coronary is
// not), then one with x = r + d(r) within 10 um, then the one whose offset is nearer the
// neighbour's
Eigen::Vector3d wire_node_rest_point(const LumenMotion& motion, const Eigen::Vector3d& x_m,
                                     const Eigen::Vector3d& own_offset_m, const Eigen::Vector3d* neighbour_offset_m,
                                     double a);

inline constexpr int kRestPointSteps = 8;
inline constexpr double kRestPointJumpM = 0.5e-3;

}  // namespace pcisim::physics
