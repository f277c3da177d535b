#pragma once
// Stage (a) of the CTA pipeline (docs/modeling.md): the contrast-filled lumen connected to the
// seeds, coarse, as [heart eq 1] evolves it. The front of eq 1 with a speed positive for HU within
// [lower, upper] and no curvature term, run to convergence, stops exactly at the region of such
// HU connected to the seeds: that region is computed directly (26-connected, so a narrow channel
// running diagonally through a stenosis still connects), in a fraction of the time. ITK's
// sparse-field level set (with its curvature term) can then refine it (level_set.iterations > 0);
// it is off by default, having measured to cut thin vessels apart. Thresholds come from the
// seeds: lower a fraction of the way from the tissue to the seed's HU, upper below calcium.
// Before cropping, pieces of lumen the region lost at a tight stenosis are bridged to it
// (gap_bridging.h).
#include <Eigen/Core>
#include <vector>
#include "anatomy/volume/volume.h"
#include "modeling/cta/gap_bridging.h"
#include "modeling/image/image3.h"
#include "modeling/image/itk_filters.h"

namespace pcisim::modeling {

// thin vessels the thresholds lose (their partial-volume peak under the lower threshold, more so
// after smoothing): the voxels that lie on a bright tube (Frangi's vesselness over scales
// sigma_min..sigma_max, modeling/image/vesselness.h) and are brighter than min_hu in the CT, within
// margin_mm of the region's box, form 26-connected pieces; a piece at least min_piece_mm long that
// comes within join_mm of the region (through voxels >= min_hu: where a thin vessel leaves a larger
// one the larger one's edge makes it no tube) joins it, with the voxels between, in rounds.
// Sheets (the myocardium's edge), blobs (chambers) and noise are not tubes.
// On by default (issue #30, docs/modeling.md): distal vessels whose contrast fades under the
// lower threshold were cut short (the family's missed centerline); the vesselness is computed at
// the candidate voxels alone (modeling/image/vesselness.h).
struct TubeGrowthOptions {
  bool enabled = true;
  double sigma_min_mm = 0.4, sigma_max_mm = 1.0;
  int sigma_steps = 3;
  double gamma_hu = 100;      // Frangi's c: the structure strength that counts as a vessel's
  double min_measure = 0.1;   // vesselness a voxel needs
  double min_hu = 0;          // and this much HU in the CT: fat (-100) joins only where noise lifts it
  double join_mm = 2.0;       // a tube piece this near the region (through voxels >= min_hu) joins it
  double min_piece_mm = 3.0;  // a piece shorter than this (its box's diagonal) is noise
  // the region's large lumens (an opening by a ball of this radius, as the clipping's) are no
  // anchors: pieces join thin parts only. Large lumens of bright structures the fill never reached
  // count below too. Distances to a large lumen are measured to the layer of voxels touching it
  // (distance_inside_mm: its zero is a mask's boundary), so they read about a voxel short
  double large_radius_mm = 3.0;
  // tube voxels within this of a large lumen are no candidates: a chamber's or the aorta's blurred
  // edge is no tube, and the rest of a vessel that comes this near one is no longer refused whole
  // for touching it (family seed 8's distal right coronary, its piece touching the right atrium
  // at one end: 40 mm missed; on the tuning split 1.0 mm raised five cases' OV, seed 3's 0.764 ->
  // 0.855, and the 5th percentile 0.756 -> 0.814; 1.5 mm no better). Negative: off; then a piece
  // touching a large lumen joins nowhere (with the rule on, no candidate touches one)
  double clear_of_large_mm = 1.0;
  // nor does a piece that runs along a large lumen: more than along_large_fraction of its voxels
  // within along_large_mm of it (the blurred edge of the descending aorta beside the lung made a
  // tube 130 mm long, a voxel off the edge, that a circumflex passing by took into its tree:
  // family seed 20, issue #30)
  double along_large_mm = 1.5;
  double along_large_fraction = 0.5;
  double margin_mm = 12;      // around the region's box
  double max_fraction = 0.5;  // the growth stops at this share of the region's voxels (a leak)
};

// a stent: its struts are brighter than the upper threshold, so the fill keeps out of them and
// follows the blurred rim outside them (a false tube round the stent) or stops there. A bright
// piece (26-connected, above the upper threshold in the image the fill sees) touching the region
// is taken into it when it is stent-like: at most max_volume_mm3 (a rib, a vertebra or the
// sternum is far larger), at least min_length_mm along its principal axis (a calcified plaque is
// shorter) and 95 % of it within max_radius_mm of that axis (a coronary stent is at most ~4 mm across).
struct MetalOptions {
  bool enabled = true;
  double max_volume_mm3 = 600;
  double min_length_mm = 8;
  double max_radius_mm = 4;  // 95 % of its voxels within this of its principal axis (a coronary stent is <= 4 mm)
};

struct SegmentationOptions {
  double min_seed_hu = 200;     // a seed must sit in contrast: mean HU within 1.5 mm above this
  double tissue_hu = 40;        // unenhanced soft tissue, the dark side of every lumen edge
  double lower_fraction = 0.3;  // lower threshold = tissue + fraction (seed HU - tissue),
  double noise_sigmas = 3.5;    // and at least this many noise sigmas (measured at the seed) above tissue
  double calcium_hu = 650;      // upper threshold: brighter is calcium or bone, never lumen
  // the fill sees the CT smoothed by a Gaussian of this sigma (mm; 0: the CT as it is): noise that
  // strings voxels of a chamber or of the myocardium near the threshold into a sponge reaching the
  // coronaries is averaged away, and the noise the lower threshold keeps clear of is the smoothed
  // image's (issue #30: family phantoms 3 and 8, myocardium 133 HU under 39 HU of noise). Off by
  // default: alone it loses thin vessels (their blurred peaks fall under the threshold: the family's
  // missed centerline rose to ~300 mm a case); with the tube growth (below) it is the robust fill
  double smoothing_mm = 0;
  double max_region_fraction = 0.25;  // a region over this share of the volume is a leak (refused)
  int connectivity = 26;              // 6 (faces) or 26 (faces, edges, corners)
  int margin_voxels = 6;              // the crop around the region
  // vessels beyond a stenosis too tight to see joined to the region before it is cropped
  GapBridgingOptions bridging;
  TubeGrowthOptions tubes;
  MetalOptions metal;
  // thresholds are filled in from the above. Off by default (iterations 0): on the phantom CTAs
  // at 0.6 mm voxels it cut 2-3 voxel wide vessels apart (the LCx kept 31 of 82 mm, with or
  // without its curvature term), where the 26-connected region keeps them; docs/modeling.md
  LevelSetOptions level_set = {.iterations = 0};
  int threads = 0;
};

struct LumenSegmentation {
  Mask mask;                                // the lumen, on the crop grid
  FloatImage hu;                            // the CT's HU on the crop grid
  std::array<int64_t, 3> crop_lo{0, 0, 0};  // the crop's first voxel in the CT
  double seed_hu = 0;                       // mean HU around the first seed
  double noise_hu = 0;                      // standard deviation of HU within 3 mm of the first seed
  double smoothed_noise_hu = 0;             // the same in the smoothed image the fill sees
  double lower_hu = 0, upper_hu = 0;
  int64_t region_voxels = 0;  // after the region growing
  int64_t tube_voxels = 0;    // added by the tube growth
  int64_t metal_voxels = 0;   // stent struts taken in (MetalOptions)
  int metal_pieces = 0;
  double tube_seconds = 0;
  std::vector<Bridge> bridges;
  double bridging_seconds = 0;
  int level_set_iterations = 0;
};

// the standard deviation of HU within radius_mm of p_mm (0 with fewer than 2 voxels)
double noise_hu_near(const anatomy::Volume& ct, const Eigen::Vector3d& p_mm, double radius_mm);

// the mean HU within radius_mm of p_mm (nearest voxels); NaN when p_mm is outside the volume
double mean_hu_near(const anatomy::Volume& ct, const Eigen::Vector3d& p_mm, double radius_mm);

// throws ModelingError naming the seed for a seed outside the CT or not in contrast, and naming
// the region's size for a leak
LumenSegmentation segment_lumen(const anatomy::Volume& ct, const std::vector<Eigen::Vector3d>& seeds_mm,
                                const SegmentationOptions& options);

}  // namespace pcisim::modeling
