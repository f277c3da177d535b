#pragma once
// PbdSystem's parallel Jacobi step (SolverKind::kJacobi: soft-tissue paper eq 7, per-particle or
// per-constraint averaging, SOR w, XPBD lambdas) on a CUDA device, in double precision.
//
// PbdSystem::step builds one on the first step with SolverKind::kJacobiCuda and keeps it; it is
// public for its timings and for pbd_cuda_available(). Built from a finalized system, it uploads
// the topology once (distance, bending, clusters with their chunked reductions and volumes, CSR
// gathers, masses) and sizes every device buffer; a step allocates nothing (a CUDA graph of the
// whole step is re-captured only when dt, the PbdParams or the contacts' setup change). Each step
// uploads what the caller may have edited since the last one (positions, velocities, states and
// inverse masses as they are then, driven targets, cluster rotations and compliances, the contact
// bodies' substeps), runs predict, the contacts (device_contacts.h: find, stabilise, one pass after
// every iteration, the forces), the Jacobi iterations and update on the device, and copies
// positions, velocities, states, rotations and the contacts' results back.
// Agreement with the CPU twin is measured in tests/physics/pbd/pbd_cuda_solver_test.cc.
#include <memory>
#include <string>

#include "physics/pbd/contact_projector.h"
#include "physics/pbd/pbd_params.h"

namespace pcisim::physics::pbd {

class PbdSystem;

// true when this build has CUDA and a device can be used; otherwise false and, if why is
// given, the reason
bool pbd_cuda_available(std::string* why = nullptr);
// the name of the device a solver would use (for benchmark reports); empty when none
std::string pbd_cuda_device_name();

struct PbdCudaStepTimings {
  double upload_ms = 0.0;    // host -> device, CUDA events
  double kernels_ms = 0.0;   // the whole step's kernels (substeps x iterations), CUDA events
  double download_ms = 0.0;  // device -> host, CUDA events
  bool graph = false;        // the kernels ran as one captured CUDA graph
};

class PbdCudaSolver {
 public:
  // throws std::invalid_argument naming kJacobiCuda when there is no CUDA build or no device;
  // std::runtime_error on a CUDA error
  explicit PbdCudaSolver(const PbdSystem& system);
  ~PbdCudaSolver();
  PbdCudaSolver(const PbdCudaSolver&) = delete;
  PbdCudaSolver& operator=(const PbdCudaSolver&) = delete;

  // the substeps of one PbdSystem::step (after its quarantine of non-finite inputs), on the
  // device; system must be the one this was built from (same sizes, checked). contacts: null, or
  // one whose device_setup() is true for this system's particles (checked)
  void run_step(PbdSystem& system, double dt_s, const PbdParams& params, ContactProjector* contacts = nullptr);
  const PbdCudaStepTimings& last_timings() const { return timings_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  PbdCudaStepTimings timings_;
};

}  // namespace pcisim::physics::pbd
