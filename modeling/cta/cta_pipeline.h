#pragma once
// The CTA pipeline of the heart paper, sections 2-3 (docs/modeling.md): a coronary CT angiogram
// and one seed in the ascending aorta in, a case (centerlines with radii and names, the lofted
// lumen, the CT) out. Stages, each its own object:
//   (a) segment_lumen         coarse lumen [heart eq 1]          modeling/cta/lumen_segmentation.h
//       bridge_gaps           vessels past a stenosis joined     modeling/cta/gap_bridging.h
//   (b) clip_to_coronaries    aorta + coronary trees             modeling/cta/coronary_clipping.h
//   (c) trace_centerlines     minimal paths with topology        modeling/cta/centerline_tracing.h
//       fit_and_sample        cubic B-spline per branch          modeling/cta/centerline_spline.h
//   (d) cross_section_radius  2-D level set per sample [eq 2]    modeling/cta/cross_section_radius.h
//       drop_dark_branches    veins cut away; abrupt ends noted modeling/cta/branch_checks.h
//   (f) label_coronary_trees  aorta, LM, LAD, LCx, RCA, D, OM    modeling/cta/coronary_labels.h
//   (g) place_template_heart  the template heart under the tree modeling/heart/heart_placement.h
//       fit_heart_elastic     its mesh fitted to the CT's heart  modeling/heart/heart_elastic_fit.h
//   (e) stitch_lumen          one closed surface, joined at      anatomy/vessel/lumen_surface.h
//                             bifurcations (or loft_lumen tubes) anatomy/vessel/lumen_mesh.h
#include <functional>
#include <string>
#include <vector>
#include "anatomy/case/case.h"
#include "anatomy/vessel/lumen_mesh.h"
#include "anatomy/vessel/lumen_surface.h"
#include "modeling/cta/branch_checks.h"
#include "modeling/cta/centerline_spline.h"
#include "modeling/cta/centerline_tracing.h"
#include "modeling/cta/coronary_clipping.h"
#include "modeling/cta/coronary_labels.h"
#include "modeling/cta/cross_section_radius.h"
#include "modeling/cta/lumen_segmentation.h"
#include "modeling/heart/heart_elastic_fit.h"
#include "modeling/heart/heart_placement.h"

namespace pcisim::modeling {

// the fill again when the first made a sponge that took a coronary tree (issue #30): noise that
// strings the voxels of a chamber or of the myocardium near the lower threshold into one region
// joins it to the aortic root, and a coronary tree that leaves the root there is cut away with it
// (clipping refuses the sponge by its volume: Clipping::root_sponges). When a sponge touches the
// root and fewer than two trees were kept, or a kept tree reaches under short_tree_mm from its
// ostium (a fragment beside the sponge that took the real tree: family seed 15's right atrium at
// 207 HU under 41 HU of noise took the RCA, and a 28 mm piece by the root was kept), the fill and
// the clipping run again on the CT smoothed by smoothing_mm (SegmentationOptions::smoothing_mm:
// the noise averaged away; the tube growth, when on, follows the thin vessels the smoothing
// loses), and that fill is kept when it finds more trees (where a short tree asked for it, reaching
// as far in all), or as many reaching further_factor times as far in all (and does not fail). Only then: on the other
// CTs the smoothed fill is the worse one (docs/modeling.md)
struct RefillOptions {
  bool enabled = true;
  double smoothing_mm = 0.5;
  double short_tree_mm = 40.0;
  double further_factor = 1.1;
};

struct CtaPipelineOptions {
  SegmentationOptions segmentation;
  ClippingOptions clipping;
  RefillOptions refill;
  TracingOptions tracing;
  SplineOptions spline;
  RadiusOptions radius;
  int radius_median_window = 5;  // samples; a median along the branch removes single bad sections
  BranchCheckOptions checks;
  LabelOptions labels;
  HeartPlacementOptions heart;
  HeartElasticFitOptions heart_fit;
  anatomy::LumenMeshSpec lumen;               // the tubes, when stitched is false
  anatomy::StitchedLumenSpec stitched_lumen;  // the one surface, when stitched is true
  bool stitched = true;                       // stage (e): one stitched surface, else one tube per branch
  bool loft = true;
  int threads = 0;  // 0: all cores
  // the memory the pipeline may take: a CT whose estimate is over it is refused before any work
  // (estimate: the CT, a mask of it, and work on a crop of at most a quarter of it at ~28 bytes a
  // voxel, i.e. 10 bytes a voxel of the CT; 4 more with the smoothed fill's float copy of the CT,
  // 7 more with the tube growth's work on its crop: 17 at the defaults)
  double memory_limit_gb = 4.0;
};

// what one stage did: its time, its counts, and what a person should know
struct StageReport {
  std::string name;
  double seconds = 0;
  std::vector<std::pair<std::string, double>> figures;
  std::vector<std::string> notes;
};

struct CtaModel {
  anatomy::Case model;  // vessels, lumen, landmarks; the CT is left to the caller (it owns it)
  std::vector<StageReport> stages;
};

// called as each stage starts and ends (for a terminal's progress lines)
using StageProgress = std::function<void(const StageReport& stage, bool finished)>;

// the estimate above, in GB (smoothed: the fill sees a smoothed copy of the CT; tubes: the tube
// growth runs)
double estimated_memory_gb(const anatomy::Volume& ct, bool smoothed, bool tubes);

// throws ModelingError with the input at fault named (a seed, a CTA without coronaries, a CT over
// the memory bound)
CtaModel build_cta_model(const anatomy::Volume& ct, const std::vector<Eigen::Vector3d>& seeds_mm,
                         const CtaPipelineOptions& options, const StageProgress& progress = nullptr);

}  // namespace pcisim::modeling
