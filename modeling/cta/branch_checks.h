#pragma once
// Checks on the traced trees before they are named (docs/modeling.md):
//  - a vein touching an artery: in the arterial phase a cardiac vein holds less contrast than the
//    artery beside it, so a branch whose lumen is much darker than its parent's where it leaves
//    (median HU on the centerline, over samples of radius >= min_radius_mm, where partial volume
//    does not darken the centre) is cut away with everything beyond it;
//  - a tree that stops while still wide: a leaf whose last samples are wider than
//    abrupt_end_radius_mm ends at an occlusion or a stenosis too tight to see (not a vessel
//    tapering out); the report says where.
#include <string>
#include <vector>
#include "modeling/cta/coronary_labels.h"
#include "modeling/image/image3.h"

namespace pcisim::modeling {

struct BranchCheckOptions {
  double vein_hu_ratio = 0.75;  // darker than this share of the parent's contrast: a vein
  double tissue_hu = 40;        // contrast is HU above this
  double min_radius_mm = 1.0;   // samples narrower than this are not compared
  double abrupt_end_radius_mm = 0.8;
};

// removes the dark branches (and their subtrees) from the tree; one note per branch removed
std::vector<std::string> drop_dark_branches(ModelTree* tree, const FloatImage& hu, const BranchCheckOptions& options);

// one note per leaf that ends wide
std::vector<std::string> find_abrupt_ends(const ModelTree& tree, const BranchCheckOptions& options);

}  // namespace pcisim::modeling
