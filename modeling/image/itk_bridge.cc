// ITK only (see itk_bridge.h): no pcisim header that pulls in the system Eigen may be included here
#include "modeling/image/itk_bridge.h"
#include "modeling/image/itk_bridge_image.h"

#include <itkImage.h>
#include <itkSymmetricSecondRankTensor.h>
#include <itkSignedMaurerDistanceMapImageFilter.h>
#include <itkThresholdSegmentationLevelSetImageFilter.h>

#include <algorithm>
#include <cstring>

namespace pcisim::modeling::itk_bridge {
namespace {

using MaskImage = itk::Image<uint8_t, 3>;
using RealImage = itk::Image<float, 3>;

}  // namespace

void distance_inside_mm(const Grid& grid, const uint8_t* mask, float* out, int threads) {
  auto f = itk::SignedMaurerDistanceMapImageFilter<MaskImage, RealImage>::New();
  f->SetInput(to_itk<uint8_t>(grid, mask));
  f->SetInsideIsPositive(true);
  f->SetSquaredDistance(false);
  f->SetUseImageSpacing(true);
  f->SetBackgroundValue(0);
  if (threads > 0) f->SetNumberOfWorkUnits(threads);
  f->Update();
  const float* p = f->GetOutput()->GetBufferPointer();
  for (size_t n = 0; n < voxels(grid); ++n) out[n] = std::max(0.0f, p[n]);
}

int threshold_level_set(const Grid& grid, const float* feature, const uint8_t* initial, const LevelSetParams& p,
                        uint8_t* out) {
  // the initial Phi: signed distance (voxels) to the initial region's boundary, negative inside
  auto sd = itk::SignedMaurerDistanceMapImageFilter<MaskImage, RealImage>::New();
  sd->SetInput(to_itk<uint8_t>(grid, initial));
  sd->SetInsideIsPositive(false);
  sd->SetUseImageSpacing(false);
  sd->SetBackgroundValue(0);
  if (p.threads > 0) sd->SetNumberOfWorkUnits(p.threads);
  sd->Update();

  auto ls = itk::ThresholdSegmentationLevelSetImageFilter<RealImage, RealImage>::New();
  ls->SetInput(sd->GetOutput());
  ls->SetFeatureImage(to_itk<float>(grid, feature));
  ls->SetLowerThreshold(p.lower);
  ls->SetUpperThreshold(p.upper);
  ls->SetPropagationScaling(p.propagation);
  ls->SetCurvatureScaling(p.curvature);
  ls->SetMaximumRMSError(p.max_rms);
  ls->SetNumberOfIterations(p.iterations);
  ls->SetIsoSurfaceValue(0.0);
  if (p.threads > 0) ls->SetNumberOfWorkUnits(p.threads);
  ls->Update();
  const float* phi = ls->GetOutput()->GetBufferPointer();
  for (size_t n = 0; n < voxels(grid); ++n) out[n] = phi[n] < 0.0f ? 1 : 0;
  return static_cast<int>(ls->GetElapsedIterations());
}

}  // namespace pcisim::modeling::itk_bridge
