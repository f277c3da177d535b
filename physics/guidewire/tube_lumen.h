#pragma once
// An analytic lumen: the union of capsules along each branch's centerline (radius interpolated
// along a segment). Segments are binned on a coarse grid so a query looks at a few of them: the
// nearest of its bin's tubes, which within the band of a wall is the nearest of all; a query in a
// bin of no tube walks a bounding-volume tree to the nearest of all. Farther out than the band, a
// bin's nearest tube is a nearby one, not always the nearest: docs/guidewire.md ("Measured
// errors", the far-field fix) says why the rod's contact keeps it so. Used by tests, as the contact geometry
// while no SDF is given, and as the SDF's answer beyond its band.
#include <vector>

#include "physics/guidewire/lumen_query.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::physics {

class TubeLumen final : public LumenQuery {
 public:
  // bin_m: edge of the binning cells (> 0); band_m: how far outside the wall distances stay exact
  // (>= 0). Throws std::invalid_argument otherwise
  explicit TubeLumen(const anatomy::VesselTree& tree, double bin_m = 3e-3, double band_m = 1e-3);
  WallSample sample(const Eigen::Vector3d& p_m) const override;

 private:
  struct Segment {
    Eigen::Vector3d a, b;
    double ra = 0.0, rb = 0.0;
  };
  // a box around the capsules below it (the axis' box grown by the radius); a leaf (left < 0)
  // holds the segments order_[first, first + count)
  struct BoxNode {
    Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
    int first = 0, count = 0, left = -1, right = -1;
  };
  void consider(const Segment& s, const Eigen::Vector3d& p, WallSample& best) const;
  int build_tree(int first, int count);
  void nearest_by_tree(const Eigen::Vector3d& p, WallSample& best) const;

  std::vector<Segment> segments_;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  double bin_m_ = 0.0;
  std::vector<int> bin_start_, bin_items_;  // CSR lists of segments per bin
  std::vector<BoxNode> tree_;
  std::vector<int> order_;  // segment indices, grouped by leaf
};

}  // namespace pcisim::physics
