#pragma once
// The ITK filters the pipeline uses, behind plain types: including this header costs nothing of
// ITK (only itk_filters.cc includes ITK's headers, which take seconds per translation unit).
#include "modeling/image/image3.h"

namespace pcisim::modeling {

// distance (mm) from each voxel of the mask to the nearest voxel outside it (Maurer's exact
// Euclidean distance transform, spacing-aware; ITK SignedMaurerDistanceMapImageFilter); 0 outside
FloatImage distance_inside_mm(const Mask& mask, int threads);

// the level-set evolution of [heart eq 1], Phi(t) = Phi(t - dt) + dt F |grad Phi|, with ITK's
// sparse-field ThresholdSegmentationLevelSetImageFilter: F is the intensity speed (positive for
// HU within [lower, upper], falling off linearly outside) minus curvature_weight times the mean
// curvature. Starts from `initial` (its boundary is the zero level set) and runs until the RMS
// change of Phi falls below max_rms_change or `iterations` is reached; the result is the region
// Phi < 0. iterations_done reports how many ran.
struct LevelSetOptions {
  double lower_hu = 200, upper_hu = 700;
  double propagation_weight = 1.0;
  double curvature_weight = 0.5;
  int iterations = 20;
  double max_rms_change = 0.02;
  int threads = 0;
};
Mask threshold_level_set(const FloatImage& hu, const Mask& initial, const LevelSetOptions& options,
                         int* iterations_done = nullptr);

}  // namespace pcisim::modeling
