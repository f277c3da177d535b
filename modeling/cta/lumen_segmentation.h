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

struct SegmentationOptions {
  double min_seed_hu = 200;           // a seed must sit in contrast: mean HU within 1.5 mm above this
  double tissue_hu = 40;              // unenhanced soft tissue, the dark side of every lumen edge
  double lower_fraction = 0.3;        // lower threshold = tissue + fraction (seed HU - tissue),
  double noise_sigmas = 3.5;          // and at least this many noise sigmas (measured at the seed) above tissue
  double calcium_hu = 650;            // upper threshold: brighter is calcium or bone, never lumen
  double max_region_fraction = 0.25;  // a region over this share of the volume is a leak (refused)
  int connectivity = 26;              // 6 (faces) or 26 (faces, edges, corners)
  int margin_voxels = 6;              // the crop around the region
  // vessels beyond a stenosis too tight to see joined to the region before it is cropped
  GapBridgingOptions bridging;
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
  double lower_hu = 0, upper_hu = 0;
  int64_t region_voxels = 0;  // after the region growing
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
