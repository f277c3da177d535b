#pragma once
// Wall contact geometry from the signed distance field of the lofted lumen (paper IV-B: SDF,
// trilinear distance, normal from the analytic gradient). The SDF is exact only within its
// band of the wall and flat beyond it (no direction), so points further out than the band, or
// off the grid, are answered by the analytic capsule lumen, which points back to the nearest
// vessel from anywhere.
#include <memory>
#include <utility>

#include "physics/guidewire/lumen_query.h"
#include "physics/guidewire/tube_lumen.h"
#include "physics/sdf/signed_distance_field.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::physics {

class SdfLumen final : public LumenQuery {
 public:
  // builds the field at spacing_m (see build_lumen_sdf); throws std::invalid_argument on a
  // spacing the grid cannot hold
  SdfLumen(const anatomy::VesselTree& tree, double spacing_m);
  // around a field already built for this tree (build_lumen_sdf; tests share one between worlds)
  SdfLumen(const anatomy::VesselTree& tree, SignedDistanceField field);
  WallSample sample(const Eigen::Vector3d& p_m) const override;

  const SignedDistanceField& field() const { return sdf_; }

 private:
  SignedDistanceField sdf_;
  TubeLumen far_;
  double trust_m_ = 0.0;  // distances below this come from the field
};

}  // namespace pcisim::physics
