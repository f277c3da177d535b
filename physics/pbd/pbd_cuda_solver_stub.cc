// PbdCudaSolver in a build without CUDA: it cannot be built, and says why (the real one is
// pbd_cuda_solver.cu, compiled only when PCISIM_HAVE_CUDA).
#ifndef PCISIM_HAVE_CUDA
#include <stdexcept>

#include "physics/pbd/pbd_cuda_solver.h"
#include "physics/pbd/pbd_system.h"

namespace pcisim::physics::pbd {

struct PbdCudaSolver::Impl {};

bool pbd_cuda_available(std::string* why) {
  if (why) *why = "this build has no CUDA (nvcc was not found at configure time)";
  return false;
}

std::string pbd_cuda_device_name() {
  return {};
}

PbdCudaSolver::PbdCudaSolver(const PbdSystem&) {
  throw std::invalid_argument("pbd: solver kJacobiCuda needs CUDA, and this build has none");
}

PbdCudaSolver::~PbdCudaSolver() = default;

void PbdCudaSolver::run_step(PbdSystem&, double, const PbdParams&, ContactProjector*) {
  throw std::invalid_argument("pbd: solver kJacobiCuda needs CUDA, and this build has none");
}

}  // namespace pcisim::physics::pbd
#endif
