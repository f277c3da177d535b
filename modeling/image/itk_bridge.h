#pragma once
// The only door to ITK: plain arrays and numbers, no Eigen. ITK 5.2 carries its own copy of Eigen,
// which must not meet the system Eigen the rest of pcisim uses in one translation unit, so
// itk_bridge.cc includes ITK and nothing of pcisim's Eigen; itk_filters.{h,cc} wrap these calls in
// the pipeline's types.
#include <cstdint>

namespace pcisim::modeling::itk_bridge {

struct Grid {
  int64_t dims[3];
  double spacing_mm[3];
  double origin_mm[3];
  double direction[9];  // row-major
};

// SignedMaurerDistanceMapImageFilter: distance (mm, spacing-aware) from each set voxel to the
// nearest unset voxel's boundary, 0 outside
void distance_inside_mm(const Grid& grid, const uint8_t* mask, float* out, int threads);

struct LevelSetParams {
  double lower, upper, propagation, curvature, max_rms;
  int iterations, threads;
};

// ThresholdSegmentationLevelSetImageFilter from the region `initial`; writes the region Phi < 0 to
// `out` and returns the iterations run
int threshold_level_set(const Grid& grid, const float* feature, const uint8_t* initial, const LevelSetParams& p,
                        uint8_t* out);

// diffeomorphic demons (Vercauteren et al. 2007; ITK's DiffeomorphicDemonsRegistrationFilter,
// symmetric gradient) in a multi-resolution pyramid (MultiResolutionPDEDeformableRegistration),
// coarsest level first. Fixed and moving share `grid`. The displacement u, 3 floats per voxel
// (x fastest; mm along the physical axes), satisfies fixed(x) ~ moving(x + u(x)). Returns the
// demons metric (mean squared intensity difference) of the finest level's last iteration.
struct DemonsParams {
  int levels = 3;
  int iterations[8] = {};  // per level, coarsest first
  double field_sigma_vox;  // Gaussian smoothing of the displacement field, voxels of the level
  double max_step_vox;     // the largest update per iteration, voxels (0: no limit)
  int threads;             // 0: ITK's default
};
double diffeomorphic_demons(const Grid& grid, const float* fixed, const float* moving, const DemonsParams& p,
                            float* field_mm);

}  // namespace pcisim::modeling::itk_bridge
