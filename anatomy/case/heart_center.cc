#include "anatomy/case/heart_center.h"

namespace pcisim::anatomy {

Eigen::Vector3d heart_center_mm(const Case& c) {
  for (const Landmark& l : c.landmarks) {
    if (l.name == "heart centre") return l.position_m * 1e3;
  }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const VesselBranch& b : c.vessels.branches) {
    if (b.name == "aorta") continue;
    for (const CenterlinePoint& p : b.points) {
      lo = lo.cwiseMin(p.position_m);
      hi = hi.cwiseMax(p.position_m);
    }
  }
  if (!(lo.array() <= hi.array()).all()) return Eigen::Vector3d::Zero();
  return 0.5 * (lo + hi) * 1e3;
}

}  // namespace pcisim::anatomy
