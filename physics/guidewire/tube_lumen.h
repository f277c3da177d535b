#pragma once
// An analytic lumen: the union of capsules along each branch's centerline (radius interpolated
// along a segment). Segments are binned on a coarse grid so a query looks at a few of them.
// Used by tests and as the contact geometry while no SDF is given.
#include <vector>

#include "physics/guidewire/lumen_query.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::physics {

class TubeLumen final : public LumenQuery {
 public:
  // bin_m: edge of the binning cells; band_m: how far outside the wall distances stay exact
  explicit TubeLumen(const anatomy::VesselTree& tree, double bin_m = 3e-3, double band_m = 1e-3);
  WallSample sample(const Eigen::Vector3d& p_m) const override;

 private:
  struct Segment {
    Eigen::Vector3d a, b;
    double ra = 0.0, rb = 0.0;
  };
  void consider(const Segment& s, const Eigen::Vector3d& p, WallSample& best) const;

  std::vector<Segment> segments_;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  double bin_m_ = 0.0;
  std::vector<int> bin_start_, bin_items_;  // CSR lists of segments per bin
};

}  // namespace pcisim::physics
