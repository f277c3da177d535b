#pragma once
// The cheap, serial part of building an SDF, shared by the CPU and CUDA twins: the grid box, the
// bricks that the triangles' bands touch, the mesh's connected components (one closed tube each)
// and each component's parity rows. The heavy part (exact distances) runs on whichever twin.
#include <cstdint>
#include <vector>

#include "anatomy/mesh/triangle_mesh.h"
#include "physics/sdf/sdf_kernels.h"

namespace pcisim::physics::sdf {

struct ComponentPlan {
  std::vector<uint32_t> triangles;  // indices into BuildPlan::triangles
  std::vector<int32_t> bricks;      // pool bricks touched by this component's bands
  int lo[3], hi[3];                 // grid-point box of the component (inclusive)
  int j0 = 0, j1 = -1, k0 = 0, k1 = -1;
  std::vector<int32_t> row_begin;  // parity rows, see ParityView
  std::vector<double> xs;
  ParityView parity() const { return {j0, j1, k0, k1, row_begin.data(), xs.data()}; }
};

struct BuildPlan {
  BuildGrid grid{};                        // grid.table points into table
  std::vector<int32_t> table;              // kBrickOutside until classified; >= 0 pool brick
  std::vector<int32_t> pool_brick_coords;  // 3 per pool brick
  std::vector<Triangle> triangles;
  std::vector<ComponentPlan> components;
  int32_t pool_bricks() const { return static_cast<int32_t>(pool_brick_coords.size() / 3); }
};

// the largest grid, in grid points: indices into it are int32 (the brick table itself is small,
// one int32 per 512 points; the guidewire bench's 0.1 mm field over the phantom is 1.6 G points)
inline constexpr int64_t kMaxGridPoints = 2147483647;
// the most grid points in stored (band) bricks: 4 bytes each in the field and 8 more for the
// build's nearest-triangle keys, so 1.5 GB at the limit; the phantom at 0.1 mm (the guidewire
// bench's finest field) stores 32 M, a patient's wider aorta a few times that
inline constexpr int64_t kMaxBandPoints = int64_t{1} << 27;

// throws std::invalid_argument for an empty mesh, a bad spacing/band, a grid of more than
// kMaxGridPoints, or walls whose band would store more than kMaxBandPoints. Both counts are
// checked before anything of their size is allocated: the grid's from the mesh's bounds, the
// band's while its bricks are listed (before the parity rows and the pool)
BuildPlan make_build_plan(const anatomy::TriangleMesh& mesh, double spacing_m, double padding_m, double band_m);

// after every component's values are folded into pool: points of other components' bricks that
// lie inside a component become -band, and untouched bricks inside any component become inside
void classify_remaining(BuildPlan& plan, std::vector<float>& pool);

// the CPU twin of the heavy part: per component, rasterize every triangle into nearest-triangle
// keys, then fold the component's signed values into pool (min = union of the tubes)
void fold_components_cpu(const BuildPlan& plan, std::vector<float>& pool);

}  // namespace pcisim::physics::sdf
