#include "physics/sdf/signed_distance_field.h"

#include <algorithm>
#include <stdexcept>

#include "physics/sdf/sdf_build_plan.h"
#include "physics/sdf/sdf_kernels.h"

namespace pcisim::physics {

SignedDistanceField SignedDistanceField::build(const anatomy::TriangleMesh& lumen, double spacing_m, double padding_m) {
  SdfBuildSpec spec;
  spec.spacing_m = spacing_m;
  spec.padding_m = padding_m;
  return build(lumen, spec);
}

// the paper's construction (section B, fig. 8a), per closed tube of the mesh: every triangle's
// prism of +-band along its normal, that prism's box, exact point-triangle distances (eq 13),
// sign from the face normal (eq 14); tubes folded by min (the union); the rest by ray parity.
SignedDistanceField SignedDistanceField::build(const anatomy::TriangleMesh& lumen, const SdfBuildSpec& spec) {
  sdf::BuildPlan plan = sdf::make_build_plan(lumen, spec.spacing_m, spec.padding_m, spec.band_m);
  std::vector<float> pool(int64_t(plan.pool_bricks()) * sdf::kBrickPoints, plan.grid.band);
  sdf::fold_components_cpu(plan, pool);
  sdf::classify_remaining(plan, pool);
  const auto& g = plan.grid;
  return from_parts(g.spacing, Eigen::Vector3d(g.origin[0], g.origin[1], g.origin[2]),
                    Eigen::Vector3i(g.dims[0], g.dims[1], g.dims[2]), g.band, std::move(plan.table), std::move(pool));
}

SignedDistanceField SignedDistanceField::from_parts(double spacing_m, const Eigen::Vector3d& origin_m,
                                                    const Eigen::Vector3i& dims, double band_m,
                                                    std::vector<int32_t> brick_table, std::vector<float> values_m) {
  if (dims.minCoeff() < 2 || dims.x() % kBrick || dims.y() % kBrick || dims.z() % kBrick) {
    throw std::invalid_argument("SignedDistanceField: dims must be >= 2 and multiples of 8");
  }
  const Eigen::Vector3i b = dims / kBrick;
  if (static_cast<int64_t>(brick_table.size()) != int64_t(b.x()) * b.y() * b.z()) {
    throw std::invalid_argument("SignedDistanceField: brick table size does not match dims");
  }
  for (int32_t e : brick_table) {
    if (e < sdf::kBrickInside ||
        (e >= 0 && (int64_t(e) + 1) * sdf::kBrickPoints > static_cast<int64_t>(values_m.size()))) {
      throw std::invalid_argument("SignedDistanceField: brick table entry out of range");
    }
  }
  SignedDistanceField f;
  f.spacing_m_ = spacing_m;
  f.origin_m_ = origin_m;
  f.dims_ = dims;
  f.band_m_ = band_m;
  f.brick_table_ = std::move(brick_table);
  f.values_m_ = std::move(values_m);
  return f;
}

namespace {

sdf::GridView view_of(const SignedDistanceField& f) {
  sdf::GridView g{};
  for (int a = 0; a < 3; ++a) {
    g.origin[a] = f.origin_m()[a];
    g.dims[a] = f.dims()[a];
    g.bricks[a] = f.dims()[a] / SignedDistanceField::kBrick;
  }
  g.spacing = f.spacing_m();
  g.band = static_cast<float>(f.band_m());
  g.table = f.brick_table().data();
  g.pool = f.values_m().data();
  return g;
}

}  // namespace

float SignedDistanceField::value_at(int i, int j, int k) const {
  return sdf::grid_value(view_of(*this), i, j, k);
}

// outside the grid box: sample at the nearest point of the box and add the distance from the
// box, with the gradient pointing from the box to the point (inside_grid = false). A non-finite
// point gives distance 1 m, gradient +x, inside_grid = false. See sdf::sample_grid.
SdfSample SignedDistanceField::sample(const Eigen::Vector3d& p_m) const {
  SdfSample s;
  if (values_m_.empty() && brick_table_.empty()) {  // a default-constructed field: nothing to hit
    s.distance_m = sdf::kFarDistanceM;
    s.inside_grid = false;
    return s;
  }
  const double p[3] = {p_m.x(), p_m.y(), p_m.z()};
  double g[3];
  sdf::sample_grid(view_of(*this), p, &s.distance_m, g, &s.inside_grid);
  s.gradient = Eigen::Vector3d(g[0], g[1], g[2]);
  return s;
}

void SignedDistanceField::sample_many(const Eigen::Vector3d* points_m, size_t n, SdfSample* out) const {
  for (size_t i = 0; i < n; ++i) out[i] = sample(points_m[i]);
}

}  // namespace pcisim::physics
