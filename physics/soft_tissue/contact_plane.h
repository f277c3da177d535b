#pragma once
// The plane a particle is held against: the support's top, or the probe face chosen for it.
#include <Eigen/Core>

namespace pcisim::physics::soft_tissue {

// free side: normal . x >= offset_m; normal is unit and points out of the solid
struct ContactPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset_m = 0.0;
};

}  // namespace pcisim::physics::soft_tissue
