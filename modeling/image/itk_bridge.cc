// ITK only (see itk_bridge.h): no pcisim header that pulls in the system Eigen may be included here
#include "modeling/image/itk_bridge.h"
#include "modeling/image/itk_bridge_image.h"

#include <itkHessianToObjectnessMeasureImageFilter.h>
#include <itkImage.h>
#include <itkMultiScaleHessianBasedMeasureImageFilter.h>
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

void tube_measure(const Grid& grid, const float* image, double sigma_min_mm, double sigma_max_mm, int sigma_steps,
                  double gamma, int threads, float* out) {
  using Hessian = itk::SymmetricSecondRankTensor<double, 3>;
  using HessianImage = itk::Image<Hessian, 3>;
  auto objectness = itk::HessianToObjectnessMeasureImageFilter<HessianImage, RealImage>::New();
  objectness->SetObjectDimension(1);  // a line: a tube
  objectness->SetBrightObject(true);
  objectness->SetAlpha(0.5);
  objectness->SetBeta(0.5);
  objectness->SetGamma(gamma);
  objectness->SetScaleObjectnessMeasure(false);
  auto multi = itk::MultiScaleHessianBasedMeasureImageFilter<RealImage, HessianImage, RealImage>::New();
  multi->SetInput(to_itk<float>(grid, image));
  multi->SetHessianToMeasureFilter(objectness);
  multi->SetSigmaMinimum(sigma_min_mm);
  multi->SetSigmaMaximum(sigma_max_mm);
  multi->SetNumberOfSigmaSteps(std::max(1, sigma_steps));
  multi->SetSigmaStepMethodToEquispaced();
  multi->SetNonNegativeHessianBasedMeasure(true);
  multi->SetGenerateScalesOutput(false);
  multi->SetGenerateHessianOutput(false);
  if (threads > 0) multi->SetNumberOfWorkUnits(threads);
  multi->Update();
  std::memcpy(out, multi->GetOutput()->GetBufferPointer(), voxels(grid) * sizeof(float));
}

}  // namespace pcisim::modeling::itk_bridge
