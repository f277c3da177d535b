#include "modeling/image/itk_filters.h"

#include "modeling/image/itk_bridge.h"

namespace pcisim::modeling {
namespace {

itk_bridge::Grid bridge_grid(const ImageGrid& g) {
  itk_bridge::Grid b;
  for (int a = 0; a < 3; ++a) {
    b.dims[a] = g.dims[a];
    b.spacing_mm[a] = g.spacing_mm[a];
    b.origin_mm[a] = g.origin_mm[a];
    for (int c = 0; c < 3; ++c) b.direction[3 * a + c] = g.direction(a, c);
  }
  return b;
}

}  // namespace

FloatImage distance_inside_mm(const Mask& mask, int threads) {
  FloatImage out{mask.grid, std::vector<float>(mask.v.size())};
  itk_bridge::distance_inside_mm(bridge_grid(mask.grid), mask.v.data(), out.v.data(), threads);
  return out;
}

Mask threshold_level_set(const FloatImage& hu, const Mask& initial, const LevelSetOptions& o, int* iterations_done) {
  Mask out = Mask::zeros(initial.grid);
  const itk_bridge::LevelSetParams p{
      o.lower_hu, o.upper_hu, o.propagation_weight, o.curvature_weight, o.max_rms_change, o.iterations, o.threads};
  const int it =
      itk_bridge::threshold_level_set(bridge_grid(initial.grid), hu.v.data(), initial.v.data(), p, out.v.data());
  if (iterations_done) *iterations_done = it;
  return out;
}

}  // namespace pcisim::modeling
