#include "physics/guidewire/sdf_lumen.h"

#include "physics/sdf/lumen_sdf.h"

namespace pcisim::physics {

SdfLumen::SdfLumen(const anatomy::VesselTree& tree, double spacing_m)
    : SdfLumen(tree, build_lumen_sdf(tree, spacing_m)) {}

SdfLumen::SdfLumen(const anatomy::VesselTree& tree, SignedDistanceField field) : sdf_(std::move(field)), far_(tree) {
  // the last cell before the band's clamp still has a true gradient
  trust_m_ = sdf_.band_m() - sdf_.spacing_m();
}

WallSample SdfLumen::sample(const Eigen::Vector3d& p_m) const {
  const SdfSample s = sdf_.sample(p_m);
  if (!s.inside_grid || s.distance_m > trust_m_) return far_.sample(p_m);
  WallSample w;
  w.distance_m = s.distance_m;
  w.normal = s.gradient;
  return w;
}

}  // namespace pcisim::physics
