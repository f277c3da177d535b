#pragma once
// Stage (c) of the CTA pipeline, first half (docs/modeling.md): centerlines with branch topology
// as minimal paths inside the clipped lumen (the TEASAR scheme: Sato et al., "TEASAR: tree-
// structure extraction algorithm for accurate and robust skeletons", Pacific Graphics 2000). Why
// minimal paths and not a skeleton: a thinned skeleton of a noisy segmentation sprouts a spur at
// every bump and needs pruning rules; a minimal path from the ostium to each far end is one curve
// per vessel by construction, stays centred because the step cost grows steeply toward the wall,
// and gives the tree's topology directly (each new path ends where it meets the tree).
//  - step cost between neighbouring voxels: length_mm (1 + penalty_scale (1 - d/d_max)^penalty_power),
//    d the voxel's distance to the lumen's edge, d_max the largest in the piece;
//  - repeat: the uncovered voxel farthest (in path length) from the ostium ends a new path, traced
//    back until it meets the tree; the voxels within cover_scale d + cover_min_mm of the path are
//    covered. A path reaching less than min_branch_mm beyond the covered voxels, or shorter than
//    min_branch_radii times the radius where it joins, is a bump, not a branch: covered, not kept.
#include <Eigen/Core>
#include <vector>
#include "modeling/cta/coronary_clipping.h"

namespace pcisim::modeling {

struct TracingOptions {
  double penalty_scale = 5000;
  double penalty_power = 16;
  double cover_scale = 1.6;
  double cover_min_mm = 0.8;
  double min_branch_mm = 5.0;
  double min_branch_radii = 3.0;
};

struct TracedBranch {
  std::vector<Eigen::Vector3d> points_mm;  // voxel centres, proximal (the join or the ostium) first
  std::vector<double> radius_mm;           // the distance to the lumen's edge at each
  int parent = -1;                         // index in the returned list; -1: the piece's first path
  int parent_point = -1;                   // the parent's point this branch starts on
};

// the paths of one coronary piece; the first starts at its ostium and ends at its farthest voxel
std::vector<TracedBranch> trace_centerlines(const Clipping& clipping, const CoronaryPiece& piece,
                                            const TracingOptions& options);

}  // namespace pcisim::modeling
