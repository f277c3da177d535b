#pragma once
// Stage (f) of the CTA pipeline (docs/modeling.md): the traced trees as one vessel tree with
// anatomical names where the anatomy allows them to be inferred, generic names otherwise.
//  - the aorta is the root;
//  - a tree whose ostium lies on the patient's left of the aortic centre (+x in LPS) is the left
//    coronary artery, on the right the right coronary artery (RCA); a third tree is "CA3", ...;
//  - left: the left main (LM) runs from the ostium to the first branch point within
//    lm_max_length_mm that starts a subtree of at least major_branch_mm; of its two continuations
//    the more anterior (smaller y over its first 15 mm) is the LAD, the other the LCx. No such
//    branch point: the tree is "LCA";
//  - a vessel continues where it runs on straightest: at each branch point leaving a subtree of at
//    least major_branch_mm, the branch more in line with the incoming vessel is its continuation;
//  - side branches of the LAD are diagonals D1, D2, ... and of the LCx obtuse marginals OM1, ...,
//    proximal first; anything else is named after its parent: "RCA-1", "D1-1", ...
// Every tree starts on the aortic centerline, as the phantom's trees do: the first branch's own
// line is carried back through the aortic wall to the aortic centre beside the ostium, and the
// radii of the samples next to the aorta (whose cross-sections see the aortic lumen) are taken
// from the vessel just beyond.
#include <Eigen/Core>
#include <string>
#include <vector>
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::modeling {

// a branch in millimetres, before names
struct ModelBranch {
  std::vector<Eigen::Vector3d> points_mm;
  std::vector<double> radius_mm;
  int parent = -1;  // within its tree; -1: the tree's first branch (from the ostium)
  int parent_point = -1;
};

struct ModelTree {
  std::vector<ModelBranch> branches;  // parents first
  Eigen::Vector3d ostium_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d aortic_centre_mm = Eigen::Vector3d::Zero();
};

struct LabelOptions {
  double lm_max_length_mm = 30.0;
  double major_branch_mm = 15.0;
  double point_spacing_mm = 0.5;  // of the piece put in front from the aortic centre
  double straighter_by_deg = 10;  // a side branch straighter than the continuation by this takes its place
  int direction_points = 8;       // directions at a branch point are taken over this many points
  // a tree's first samples within the aortic radius plus this of the aortic centre bend into the
  // ostium's funnel: they are replaced by the vessel's line, its direction taken over the next
  // ostium_direction_mm of the vessel
  double ostium_clearance_mm = 4.5;
  double ostium_direction_mm = 4;
};

// the named tree in metres, parents before children, "aorta" first
anatomy::VesselTree label_coronary_trees(const std::vector<anatomy::CenterlinePoint>& aorta_mm,
                                         const std::vector<ModelTree>& trees, const LabelOptions& options);

}  // namespace pcisim::modeling
