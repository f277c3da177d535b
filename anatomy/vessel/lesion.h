#pragma once
// Lesions of a vessel tree as data (issue #34 item 1): where a branch narrows, how much, over what
// length, against the diameter it would have there, as quantitative coronary angiography (QCA)
// reports a stenosis. A case names them in lesions.json (docs/anatomy.md); pcisim-model measures
// them from the radius profile it traced (detect_lesions), a phantom writes its truth, a person may
// edit them.
#include <string>
#include <vector>

#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::anatomy {

struct Lesion {
  std::string branch;        // the tree's branch name
  double position_mm = 0.0;  // arc length from the branch's first point to the narrowest point
  double length_mm = 0.0;    // the narrowed extent (diameter stenosis above the edge's fraction)
  double minimal_lumen_diameter_mm = 0.0;
  double reference_diameter_mm = 0.0;  // the healthy diameter at the narrowest point (interpolated)
  double diameter_stenosis_pct = 0.0;  // 100 (1 - MLD / reference)
  double calcified_fraction = 0.0;     // of the lesion's length with calcium, [0, 1] (0: none known)
  double eccentricity = 0.0;           // 0 concentric .. 1 all on one side (0: none known)
};

struct LesionDetection {
  // a lesion is reported where the diameter stenosis reaches this (QCA calls 50 % significant;
  // milder narrowings are still worth naming in a training case)
  double min_stenosis_pct = 30.0;
  // its extent: the points narrowed by at least this against the reference
  double edge_stenosis_pct = 10.0;
  // points narrower than this fraction of the reference fit are left out of the next fit (the fit
  // follows the healthy wall, its taper included)
  double healthy_fraction = 0.93;
  int fit_rounds = 5;
  // branches with fewer points are not measured (no healthy wall either side to refer to)
  int min_points = 12;
  // the diameters are the median of this many neighbouring points first (an odd count; 1: as they
  // are): a traced radius is noisy from point to point, QCA's edges are smoothed too
  int median_points = 5;
  // a narrowed run must leave this much of the branch either side: a run that reaches a branch's
  // end has no healthy wall beyond it to be measured against (an ostium's junction, a distal end
  // fading into the noise)
  double healthy_margin_mm = 2.0;
};

// QCA on the radius profile: per branch, the diameters smoothed by a running median, the reference
// diameter as a quadratic in arc length fitted to the healthy points (those narrower than healthy_fraction of the last
// fit left out, round by round), the diameter stenosis of each point against it, and a lesion where a run of points
// narrowed by at least edge_stenosis_pct reaches min_stenosis_pct (its narrowest point, its extent).
// Ordered by branch, then position.
std::vector<Lesion> detect_lesions(const VesselTree& tree, const LesionDetection& options = {});

// empty when the lesion fits the tree: its branch present, its position within the branch's arc
// length, diameters positive and finite with the MLD under the reference, the stenosis consistent
// with them (within 0.5 %), fractions in [0, 1]; otherwise what is wrong ("field: expected ...")
std::string validate_lesion(const Lesion& lesion, const VesselTree& tree);

}  // namespace pcisim::anatomy
