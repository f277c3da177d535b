#pragma once
// The vessel lumen as one watertight surface stitched across bifurcations: the iso-surface f = 0
// of the union of the swept spheres (cone-spheres) of every centerline segment, extracted by
// marching tetrahedra on a sparse grid. A mesh boolean of lofted tubes is fragile; this surface
// is one closed 2-manifold per connected part of the tree by construction. Method and figures:
// docs/modeling.md ("(e) Loft").
#include <cstddef>
#include <string>
#include <vector>

#include "anatomy/mesh/triangle_mesh.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::anatomy {

struct StitchedLumenSpec {
  double spacing_m = 0.2e-3;          // grid spacing
  double cells_per_min_radius = 0.0;  // > 0: the spacing is at most the smallest radius / this
  std::vector<std::string> exclude;   // branch names left out (e.g. "aorta"), as LumenMeshSpec
};

// what the extraction did (for reports and measurement)
struct StitchedLumenStats {
  double spacing_m = 0.0;
  size_t segments = 0;          // swept-sphere segments
  size_t bricks_sampled = 0;    // 8^3-node bricks holding values
  size_t bricks_inside = 0;     // bricks found wholly inside (no values stored)
  size_t memory_bytes = 0;      // the sampled values, brick tables and edge map, summed (an upper bound)
  size_t cavities_removed = 0;  // closed inner shells (pockets between overlapping spheres) dropped
};

// signed distance to the union of the swept spheres of the tree's segments (consecutive
// centerline points (a, ra), (b, rb)); exact outside the union, negative inside
double swept_sphere_distance_m(const Eigen::Vector3d& p_m, const Eigen::Vector3d& a_m, double ra_m,
                               const Eigen::Vector3d& b_m, double rb_m);

// one indexed mesh, counter-clockwise seen from outside; empty when every branch is excluded.
// Closed inner shells (pockets of f > 0 enclosed by the lumen) are dropped.
// A child branch that does not start on its parent's centerline is extended back toward it, as
// loft_lumen does, so it joins its parent (not toward an excluded parent)
TriangleMesh stitch_lumen(const VesselTree& tree, const StitchedLumenSpec& spec, StitchedLumenStats* stats = nullptr);

// number of connected components (vertices joined by triangle edges; unused vertices ignored)
int count_components(const TriangleMesh& mesh);

}  // namespace pcisim::anatomy
