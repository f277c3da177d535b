#include "modeling/image/itk_filters.h"

#include <algorithm>
#include <stdexcept>
#include <string>

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

std::string validate(const DemonsOptions& o) {
  if (o.levels < 1 || o.levels > 8) return "levels: must be 1-8, got " + std::to_string(o.levels);
  if (o.iterations < 1 || o.iterations > 10000)
    return "iterations: must be 1-10000, got " + std::to_string(o.iterations);
  if (!(o.field_sigma_vox >= 0.0 && o.field_sigma_vox <= 20.0))
    return "field_sigma_vox: must be 0-20, got " + std::to_string(o.field_sigma_vox);
  if (!(o.max_step_vox >= 0.0 && o.max_step_vox <= 20.0))
    return "max_step_vox: must be 0-20, got " + std::to_string(o.max_step_vox);
  if (o.threads < 0) return "threads: must be >= 0, got " + std::to_string(o.threads);
  return "";
}

Eigen::Vector3d DisplacementImage::at_mm(const Eigen::Vector3d& p_mm) const {
  Eigen::Vector3d c = x.grid.continuous_index(p_mm);
  for (int a = 0; a < 3; ++a) c[a] = std::clamp(c[a], 0.0, static_cast<double>(x.grid.dims[a] - 1));
  return {x.at(c, 0.0f), y.at(c, 0.0f), z.at(c, 0.0f)};
}

DisplacementImage diffeomorphic_demons(const FloatImage& fixed, const FloatImage& moving, const DemonsOptions& o,
                                       double* metric) {
  if (const std::string bad = validate(o); !bad.empty()) throw std::invalid_argument("demons: " + bad);
  const ImageGrid& g = fixed.grid;
  if (const std::string d = grid_difference(moving.grid, g); !d.empty())
    throw std::invalid_argument("demons: the moving image's " + d + " (the fixed image's grid)");
  itk_bridge::DemonsParams p;
  p.levels = o.levels;
  for (int l = 0; l < o.levels; ++l) p.iterations[l] = o.iterations;
  p.field_sigma_vox = o.field_sigma_vox;
  p.max_step_vox = o.max_step_vox;
  p.threads = o.threads;
  std::vector<float> u(3 * fixed.v.size());
  const double m = itk_bridge::diffeomorphic_demons(bridge_grid(g), fixed.v.data(), moving.v.data(), p, u.data());
  if (metric) *metric = m;
  DisplacementImage d{{g, std::vector<float>(fixed.v.size())},
                      {g, std::vector<float>(fixed.v.size())},
                      {g, std::vector<float>(fixed.v.size())}};
  for (size_t n = 0; n < fixed.v.size(); ++n) {
    d.x.v[n] = u[3 * n];
    d.y.v[n] = u[3 * n + 1];
    d.z.v[n] = u[3 * n + 2];
  }
  return d;
}

}  // namespace pcisim::modeling
