#pragma once
// The kidney's particle model stepped by PBD with contacts (issue #16 item 2; soft-tissue paper
// Algorithm 1): one PBD particle per model particle (m = density r^3), one shape-matching cluster
// per model cluster, a static support plane and a kinematic convex probe. Built once; step()
// allocates nothing.
#include <Eigen/Core>

#include "physics/pbd/pbd_params.h"
#include "physics/pbd/pbd_system.h"
#include "physics/soft_tissue/contact_plane.h"
#include "physics/soft_tissue/convex_probe.h"
#include "physics/soft_tissue/tissue_contacts.h"
#include "physics/soft_tissue/tissue_model.h"
#include "physics/soft_tissue/tissue_params.h"

namespace pcisim::physics::soft_tissue {

class TissueBody {
 public:
  // throws std::invalid_argument on bad params (validate), a support normal that is not finite
  // and non-zero, or a bad probe (normalised)
  TissueBody(const TissueModel& model, const TissueParams& params, const ContactPlane& support,
             const ConvexProbe& probe = {});
  TissueBody(const TissueBody& other);
  TissueBody& operator=(const TissueBody&) = delete;

  // where the probe is at the end of the next step (the rotation is normalised). A non-finite
  // position or rotation, or a zero quaternion, is ignored (the last target stays): returns false
  bool set_probe_pose(const ProbePose& pose);
  void step(double dt_s);

  const Eigen::Matrix3Xd& positions_m() const { return system_.particles().position_m; }
  const Eigen::Matrix3Xd& velocities_m_per_s() const { return system_.particles().velocity_m_per_s; }
  const Eigen::Matrix3Xd& rest_m() const { return rest_m_; }
  const TissueContacts& contacts() const { return contacts_; }
  const TissueParams& params() const { return params_; }
  double particle_mass_kg() const { return particle_mass_kg_; }
  int particle_count() const { return system_.particle_count(); }
  // force the tissue puts on the probe over the last step (newtons, world frame), for haptics
  const Eigen::Vector3d& probe_force_n() const { return contacts_.probe_force_n(); }
  const Eigen::Vector3d& support_force_n() const { return contacts_.support_force_n(); }
  const pbd::PbdSystem& system() const { return system_; }
  pbd::PbdSystem& system() { return system_; }

 private:
  TissueParams params_;
  pbd::PbdParams pbd_params_;
  double particle_mass_kg_ = 0.0;
  Eigen::Matrix3Xd rest_m_;
  pbd::PbdSystem system_;
  TissueContacts contacts_;
};

}  // namespace pcisim::physics::soft_tissue
