#pragma once
// The ITK filters the pipeline uses, behind plain types: including this header costs nothing of
// ITK (only itk_filters.cc includes ITK's headers, which take seconds per translation unit).
#include <string>

#include "modeling/image/image3.h"

namespace pcisim::modeling {

// distance (mm) from each voxel of the mask to the nearest voxel of its boundary (a mask voxel
// with a face neighbour outside it: 0 there, about a voxel less than the distance to the nearest
// voxel outside; Maurer's exact Euclidean distance transform, spacing-aware; ITK
// SignedMaurerDistanceMapImageFilter measures to the mask's contour); 0 outside
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

// diffeomorphic demons in a multi-resolution pyramid (itk_bridge.h): the displacement u with
// fixed(x) ~ moving(x + u(x)), one FloatImage per physical axis, mm
struct DemonsOptions {
  int levels = 3;                // pyramid levels (each halves the grid), 1-8
  int iterations = 40;           // per level
  double field_sigma_vox = 1.5;  // smoothing of the displacement field, voxels of each level
  double max_step_vox = 2.0;     // largest update per iteration, voxels
  int threads = 0;               // 0: ITK's default
};
// "" or what is wrong, naming the field
std::string validate(const DemonsOptions& o);

struct DisplacementImage {
  FloatImage x, y, z;
  // trilinear; a point beyond the grid takes the nearest boundary value
  Eigen::Vector3d at_mm(const Eigen::Vector3d& p_mm) const;
};
// throws std::invalid_argument when the options are bad or the grids differ; metric: the demons'
// mean squared intensity difference at the end
DisplacementImage diffeomorphic_demons(const FloatImage& fixed, const FloatImage& moving, const DemonsOptions& o,
                                       double* metric = nullptr);

}  // namespace pcisim::modeling
