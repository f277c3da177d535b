// ITK only (see itk_bridge.h): the demons registration, in a translation unit of its own because
// ITK's registration headers take seconds to compile
#include <itkDiffeomorphicDemonsRegistrationFilter.h>
#include <itkImage.h>
#include <itkMultiResolutionPDEDeformableRegistration.h>
#include <itkMultiThreaderBase.h>

#include "modeling/image/itk_bridge.h"
#include "modeling/image/itk_bridge_image.h"

namespace pcisim::modeling::itk_bridge {
namespace {

using RealImage = itk::Image<float, 3>;
using Field = itk::Image<itk::Vector<float, 3>, 3>;

// ITK's filters take their thread count from a process-wide default when they are made: set
// while this registration's filters are made and run, restored after (not for concurrent callers)
class ThreadCap {
 public:
  explicit ThreadCap(int threads) : before_(itk::MultiThreaderBase::GetGlobalDefaultNumberOfThreads()) {
    if (threads > 0) itk::MultiThreaderBase::SetGlobalDefaultNumberOfThreads(static_cast<itk::ThreadIdType>(threads));
  }
  ~ThreadCap() { itk::MultiThreaderBase::SetGlobalDefaultNumberOfThreads(before_); }
  ThreadCap(const ThreadCap&) = delete;
  ThreadCap& operator=(const ThreadCap&) = delete;

 private:
  itk::ThreadIdType before_;
};

}  // namespace

double diffeomorphic_demons(const Grid& grid, const float* fixed, const float* moving, const DemonsParams& p,
                            float* field_mm) {
  using Demons = itk::DiffeomorphicDemonsRegistrationFilter<RealImage, RealImage, Field>;
  using Pyramid = itk::MultiResolutionPDEDeformableRegistration<RealImage, RealImage, Field, float>;
  const ThreadCap cap(p.threads);
  auto demons = Demons::New();
  demons->SetUseGradientType(Demons::GradientType::Symmetric);
  demons->SetSmoothDisplacementField(true);
  demons->SetStandardDeviations(p.field_sigma_vox);
  demons->SetSmoothUpdateField(false);
  demons->SetMaximumUpdateStepLength(p.max_step_vox);

  auto pyramid = Pyramid::New();
  pyramid->SetRegistrationFilter(demons);
  pyramid->SetNumberOfLevels(static_cast<unsigned>(p.levels));
  std::vector<unsigned> iterations(p.iterations, p.iterations + p.levels);
  pyramid->SetNumberOfIterations(iterations.data());
  pyramid->SetFixedImage(to_itk<float>(grid, fixed));
  pyramid->SetMovingImage(to_itk<float>(grid, moving));
  pyramid->Update();

  const Field* out = pyramid->GetOutput();
  const size_t n = voxels(grid);
  const itk::Vector<float, 3>* u = out->GetBufferPointer();
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) field_mm[3 * i + a] = u[i][a];
  return demons->GetMetric();
}

}  // namespace pcisim::modeling::itk_bridge
