#pragma once
// Contacts inside the PBD step (soft-tissue paper Algorithm 1 lines 6-15): a body that collides
// with other shapes hands PbdSystem::step one of these; the step calls it at the places the
// algorithm names. It edits the particles' x and x* directly and must allocate nothing.
// A projector whose bodies are half-space sets (device_contacts.h) can also be solved by the
// CUDA solver (SolverKind::kJacobiCuda): it then describes itself with the device_* calls.
#include <Eigen/Core>

#include "physics/pbd/device_contacts.h"
#include "physics/pbd/particles.h"

namespace pcisim::physics::pbd {

class ContactProjector {
 public:
  virtual ~ContactProjector() = default;
  // after prediction (lines 6-15): find the contacts, then the stabilisation passes, which move
  // x and x* together and so add no velocity. fraction_of_step: where this substep ends, (0, 1]
  virtual void begin_substep(Particles& particles, double h_s, double fraction_of_step) = 0;
  // one pass over the contacts, after every solver iteration's constraint groups (lines 16-22)
  virtual void project(Particles& particles, double h_s) = 0;
  // after the last iteration, before velocities are updated (line 23)
  virtual void end_substep(const Particles& particles, double h_s) = 0;

  // --- the device path (pbd_cuda_solver.h); a projector that has none keeps these defaults ---
  struct DeviceSetup {
    const double* radius_m = nullptr;  // each particle's contact distance, one per particle
    int particles = 0;
    int bodies = 0;  // at most device::kMaxContactBodies; a particle's slot b is body b's
    double margin_m = 0.0;
    int stabilisation_iterations = 0;
  };
  // false: these contacts are solved on the CPU only
  virtual bool device_setup(DeviceSetup* setup) const {
    (void)setup;
    return false;
  }
  // before a step of `substeps` substeps: bodies[s * setup.bodies + b] is body b over substep s
  virtual void device_bodies(int substeps, device::ContactBody* bodies) {
    (void)substeps;
    (void)bodies;
  }
  // after it: per body the force the particles put on it (the mean over the substeps) and its
  // contacts in the last substep, and the largest stabilisation move of the step
  virtual void device_results(const Eigen::Vector3d* force_n, const int* contacts, double stabilisation_max_m) {
    (void)force_n;
    (void)contacts;
    (void)stabilisation_max_m;
  }
};

}  // namespace pcisim::physics::pbd
