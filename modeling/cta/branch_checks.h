#pragma once
// Checks on the traced trees before they are named (docs/modeling.md):
//  - a vein touching an artery: in the arterial phase a cardiac vein holds less contrast than the
//    artery beside it, so a branch whose lumen is much darker than its parent's where it leaves
//    (median HU on the centerline, over samples of radius >= min_radius_mm, where partial volume
//    does not darken the centre) is cut away with everything beyond it;
//  - a vessel crossing over another (a cardiac vein over an artery, touching it where they cross):
//    traced as two arms leaving the artery at one point in opposite directions, both at a wide
//    angle to the artery, while a third arm carries the artery on; the most nearly opposite such
//    pair of a junction is cut away (a vein may be as bright as a distal artery, so its contrast
//    cannot tell it);
//  - a vessel beside another (a cardiac vein touching an artery along its length, as bright as
//    the distal artery): the fill joins them into one ribbon and the tracer follows the second
//    as a branch running back along the first; a branch that runs along its parent (its course
//    within parallel_max_deg of the parent's direction) and stays beside it (within the two radii
//    and parallel_gap_mm) over parallel_fraction of its length beyond its first
//    parallel_skip_mm is cut away with everything beyond it (a side branch leaves at 35-80 deg);
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
  // a crossing: arms leaving within crossing_gap_mm of each other along the vessel (or leaving
  // such an arm within crossing_gap_mm of the junction, counted along both), their
  // directions over arm_mm past their first arm_skip_mm (an arm, the incoming vessel included,
  // shorter than both together is not judged); opposite when more than opposite_deg apart, across the
  // vessel when more than across_deg from its incoming direction; the vessel goes on along an arm
  // within on_deg of its incoming direction, and nearer it than either of the pair
  double crossing_gap_mm = 3.0, arm_mm = 4.0;
  // each arm's direction is taken past its first arm_skip_mm: there the traced lines bend into
  // the junction's blob of lumen (family seed 2: a vein crossing the RCA, its arms 117 deg apart
  // over their first 4 mm, 167 deg from 2 to 6 mm)
  double arm_skip_mm = 2.0;
  double opposite_deg = 130, across_deg = 35, on_deg = 60;
  // and over far_arm_mm past far_skip_mm, where the arms have left the junction's blob: opposite
  // when more than far_opposite_deg apart there
  double far_skip_mm = 6.0, far_arm_mm = 6.0, far_opposite_deg = 150;
  // where nothing goes on and the pair is all there is (a T), a pair whose arms are both wider
  // than wider_ratio times the vessel reaching them (median radii over the arms' 2-12 mm, the
  // vessel's 2-12 mm before the junction) is a vessel it ends against, cut too
  double wider_ratio = 1.5;
  double sample_spacing_mm = 0.5;  // of the branches' samples (build_cta_model sets the spline's)
  // a branch beside its parent: at least parallel_min_mm long, its course past its first
  // parallel_skip_mm within parallel_max_deg of the parent's direction where it leaves (either
  // way), and parallel_fraction of those samples within the two radii plus parallel_gap_mm of
  // the parent
  double parallel_min_mm = 8.0, parallel_skip_mm = 3.0, parallel_fraction = 0.7, parallel_gap_mm = 1.0;
  double parallel_max_deg = 20.0;
};

// removes the dark branches (and their subtrees) from the tree; one note per branch removed
std::vector<std::string> drop_dark_branches(ModelTree* tree, const FloatImage& hu, const BranchCheckOptions& options);

// removes vessels crossing over the tree (and what was traced beyond them); one note per crossing
std::vector<std::string> drop_crossings(ModelTree* tree, const BranchCheckOptions& options);

// removes branches that run beside their parent (and their subtrees); one note per branch removed
std::vector<std::string> drop_parallel_branches(ModelTree* tree, const BranchCheckOptions& options);

// one note per leaf that ends wide
std::vector<std::string> find_abrupt_ends(const ModelTree& tree, const BranchCheckOptions& options);

}  // namespace pcisim::modeling
