#pragma once
// Accuracy of an extracted coronary tree's centerlines against exact truth, by the measures of the
// Rotterdam coronary centerline evaluation (M. Schaap et al., "Standardized evaluation methodology
// and reference database for evaluating coronary artery centerline extraction algorithms",
// Medical Image Analysis 13(5):701-714, 2009).
//
// Schaap's method, in short: both centerlines are sampled at equal arc-length steps and their
// points put in correspondence. A correspondence is a true positive when its two points lie within
// the reference lumen radius of each other; a reference point without one is a false negative, an
// extracted point without one a false positive. From these: OV (overlap), the true positives of
// both sides over all points; OF (overlap until first error), the share of a reference vessel
// before its first false negative, counted from the ostium; OT (overlap with the clinically
// relevant part), OV over the part of each vessel up to its most distal point of diameter >= 1.5
// mm; AI (average inside), the mean distance over the true-positive correspondences.
//
// Where this differs from Schaap (on purpose):
//  - correspondence is the nearest point on the other tree's centerline polylines (all branches),
//    not Schaap's minimal-cost monotone matching of one vessel to one centerline: a point is never
//    forced onto a distant partner, several points may share one, and an extracted centerline that
//    runs back along itself still counts as true positive where it is close.
//  - an extracted *tree* is scored, not one extracted centerline per vessel: its points are
//    scored against the whole reference tree, and each is given to every reference vessel through
//    its nearest reference point (shared proximal parts belong to several vessels).
//  - the totals (ov, ot, ai_mm, the counts) pool each reference branch's points once (a point of
//    the LM is not counted once per vessel through it); Schaap averages per-vessel scores, which
//    `vessels` holds. `of` is the mean over vessels, as in Schaap.
//  - nothing is clipped at the ends: the aorta is left out by name (`exclude`), and extracted
//    points beyond a reference vessel's end count as false positives once farther than its radius.
// A ratio with nothing to count (no points, no true positive for AI) is NaN.
#include <string>
#include <vector>
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::modeling {

struct CenterlineScoreOptions {
  double sample_spacing_m = 0.1e-3;              // both trees resampled at this arc-length step
  double min_diameter_ot_m = 1.5e-3;             // OT stops at a vessel's last point this wide
  std::vector<std::string> exclude = {"aorta"};  // branches left out of both trees, by name
};

// one reference vessel: a path from an ostium to a distal end, named by its last branch
struct VesselScores {
  std::string name;
  double length_mm = 0;  // ostium to the distal end
  double ov = 0, of = 0, ot = 0;
  double ai_mm = 0;
  double ot_length_mm = 0;  // ostium to the most distal point at least min_diameter_ot_m wide
  double first_fn_mm = 0;   // arc length from the ostium of the first false negative; NaN if none
  int tp_reference = 0, fn = 0, tp_extracted = 0, fp = 0;
};

struct CenterlineScores {
  double ov = 0, of = 0, ot = 0;
  double ai_mm = 0;
  // |extracted radius at the nearest extracted point - reference radius| over TPR points
  double radius_error_mean_mm = 0, radius_error_p95_mm = 0;
  int tp_reference = 0, fn = 0, tp_extracted = 0, fp = 0;
  std::vector<VesselScores> vessels;  // one per distal end of the reference tree
};

// OV, OF, OT, AI and radius errors of `extracted` against `reference` (Schaap 2009, with the
// deviations above). The reference vessels are every path from an ostium (the first point of a
// branch whose parent is excluded or absent) to a branch end that no child continues. A branch
// whose first point is not its parent's point is joined to it by a straight piece.
CenterlineScores score_centerlines(const anatomy::VesselTree& reference, const anatomy::VesselTree& extracted,
                                   const CenterlineScoreOptions& options = {});

// Schaap et al. score each vessel from its ostium: `tree` with the leading points of each of its
// trees (a branch whose parent is the aorta) that lie inside the true aortic lumen (`truth`'s
// "aorta" branch and radii) cut off; the phantoms' trees and the pipeline's start on the aortic
// centerline. `tree` as it is when `truth` has no aorta.
anatomy::VesselTree outside_aorta(const anatomy::VesselTree& tree, const anatomy::VesselTree& truth);

}  // namespace pcisim::modeling
