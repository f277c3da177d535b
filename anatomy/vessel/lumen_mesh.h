#pragma once
// The vessel lumen as closed tubes lofted along the centerlines: one watertight tube per branch,
// the lumen being their union (a child's tube begins inside its parent, so junctions have no gap).
#include <string>
#include <vector>

#include "anatomy/mesh/triangle_mesh.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::anatomy {

struct LumenMeshSpec {
  int segments = 16;                   // ring vertices, at least; more where the radius needs it
  double max_chord_error_m = 0.05e-3;  // a ring's polygon sags at most this far inside the circle
  int cap_rings = 4;                   // latitude rings of each hemispherical end cap, at least
  std::vector<std::string> exclude;    // branch names left out (e.g. "aorta")
};

// one closed tube per branch, in the tree's branch order (an excluded branch gives an empty mesh).
// Rings sit on every centerline point, oriented by rotation-minimising frames (double reflection);
// both ends are closed by hemispheres, so every edge is shared by exactly two triangles and the
// faces wind counter-clockwise seen from outside (outward normals).
std::vector<TriangleMesh> loft_branch_tubes(const VesselTree& tree, const LumenMeshSpec& spec);

// all tubes in one mesh (disjoint vertex sets, so each tube stays a connected component)
TriangleMesh loft_lumen(const VesselTree& tree, const LumenMeshSpec& spec);

// the points a branch's lumen is swept along: a child that does not start on its parent's
// centerline is first extended back toward it (by at most the parent's radius there), so its lumen
// begins inside the parent's and the junction has no gap (extend_to_parent false: not extended);
// repeated points are dropped (they have no direction). Shared by the tubes and the stitched surface.
void branch_sweep_points(const VesselTree& tree, const VesselBranch& branch, bool extend_to_parent,
                         std::vector<Eigen::Vector3d>* points_m, std::vector<double>* radii_m);

// appends b to a, re-indexing b's triangles
void append_mesh(TriangleMesh& a, const TriangleMesh& b);

}  // namespace pcisim::anatomy
