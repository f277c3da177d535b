#pragma once
// The tissue's contacts with the support (a static plane) and the probe (a kinematic convex body),
// solved inside the PBD step (pbd/contact_projector.h) [soft-tissue, Algorithm 1 lines 6-15 and
// the contact group of lines 16-22], by the rules of pbd/device_contacts.h, on the CPU or, with
// SolverKind::kJacobiCuda, on the device (the device_* calls). Sized at construction; nothing
// allocates per step.
#include <Eigen/Core>
#include <vector>

#include "physics/pbd/contact_projector.h"
#include "physics/soft_tissue/contact_plane.h"
#include "physics/soft_tissue/convex_probe.h"
#include "physics/soft_tissue/tissue_params.h"

namespace pcisim::physics::soft_tissue {

class TissueContacts final : public pbd::ContactProjector {
 public:
  // contact_radius_m: each particle's contact distance (begin_substep needs one per particle);
  // support: its top plane (normal out of the
  // support); probe: normalised, may have no faces. Throws std::invalid_argument when the probe
  // has more than device::kMaxContactFaces faces
  TissueContacts(Eigen::VectorXd contact_radius_m, const TissueParams& params, const ContactPlane& support,
                 const ConvexProbe& probe);

  // where the probe is at the end of the next step (substeps move it there on a line and a slerp)
  void set_probe_target(const ProbePose& pose) { probe_target_ = pose; }
  // between steps: call before each step; the step's forces are averaged over its substeps
  void begin_step();

  void begin_substep(pbd::Particles& particles, double h_s, double fraction_of_step) override;
  void project(pbd::Particles& particles, double h_s) override;
  void end_substep(const pbd::Particles& particles, double h_s) override;
  bool device_setup(DeviceSetup* setup) const override;
  void device_bodies(int substeps, pbd::device::ContactBody* bodies) override;
  void device_results(const Eigen::Vector3d* force_n, const int* contacts, double stabilisation_max_m) override;

  const ProbePose& probe_pose() const { return probe_now_; }
  const ConvexProbe& probe() const { return probe_; }
  const ContactPlane& support() const { return support_; }
  // the largest contact distance (every particle's, with ContactSurface::kSpheres), and one particle's
  double contact_radius_m() const { return radius_m_.size() ? radius_m_.maxCoeff() : 0.0; }
  double contact_radius_m(int particle) const { return radius_m_[particle]; }
  // force the tissue puts on the probe and on the support over the last step (mean of its substeps)
  const Eigen::Vector3d& probe_force_n() const { return probe_force_n_; }
  const Eigen::Vector3d& support_force_n() const { return support_force_n_; }
  int probe_contacts() const { return probe_contacts_; }  // in the last substep
  int support_contacts() const { return support_contacts_; }
  // how far stabilisation moved particles in the last step (largest single move)
  double stabilisation_max_m() const { return stabilisation_max_m_; }

 private:
  static constexpr int kSupport = 0, kProbe = 1;  // body indices
  struct Contact {
    int particle = 0;
    int body = kSupport;
    pbd::device::ContactSlot slot;
  };
  // the support and the probe over a substep that takes the probe from `from` to `to`
  void make_bodies(const ProbePose& from, const ProbePose& to, pbd::device::ContactBody* bodies) const;
  void advance_probe(double fraction_of_step, pbd::device::ContactBody* bodies);
  void stabilise(pbd::Particles& particles);

  Eigen::VectorXd radius_m_;
  TissueParams params_;
  ContactPlane support_;
  ConvexProbe probe_;
  ProbePose probe_step_start_, probe_target_, probe_now_;
  pbd::device::ContactBody bodies_[2];  // this substep's, on the CPU
  std::vector<Contact> contacts_;       // two slots per particle (support, probe), sized once
  int count_ = 0;                       // slots in use this substep
  int probe_contacts_ = 0, support_contacts_ = 0, substeps_seen_ = 0;
  Eigen::Vector3d probe_force_n_ = Eigen::Vector3d::Zero(), support_force_n_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d probe_force_sum_n_ = Eigen::Vector3d::Zero(), support_force_sum_n_ = Eigen::Vector3d::Zero();
  double stabilisation_max_m_ = 0.0;
};

}  // namespace pcisim::physics::soft_tissue
