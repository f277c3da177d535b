#include "physics/soft_tissue/tissue_contacts.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

namespace pcisim::physics::soft_tissue {

using Eigen::Vector3d;
namespace device = pbd::device;

namespace {

device::Vec3 to_device(const Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

device::Mat3 to_device(const Eigen::Quaterniond& q) {
  device::Mat3 m;
  Eigen::Map<Eigen::Matrix3d>(m.m) = q.toRotationMatrix();
  return m;
}

device::ContactFace to_device(const ContactPlane& p) {
  return {to_device(p.normal), p.offset_m};
}

}  // namespace

TissueContacts::TissueContacts(Eigen::VectorXd contact_radius_m, const TissueParams& params,
                               const ContactPlane& support, const ConvexProbe& probe)
    : radius_m_(std::move(contact_radius_m)),
      params_(params),
      support_(support),
      probe_(probe),
      probe_step_start_(probe.pose),
      probe_target_(probe.pose),
      probe_now_(probe.pose) {
  if (probe_.faces.size() > static_cast<size_t>(device::kMaxContactFaces))
    throw std::invalid_argument("soft_tissue: the probe has " + std::to_string(probe_.faces.size()) +
                                " faces; at most " + std::to_string(device::kMaxContactFaces));
  contacts_.resize(2 * static_cast<size_t>(radius_m_.size()));
}

void TissueContacts::begin_step() {
  probe_step_start_ = probe_now_;
  probe_force_sum_n_.setZero();
  support_force_sum_n_.setZero();
  probe_force_n_.setZero();
  support_force_n_.setZero();
  substeps_seen_ = 0;
  stabilisation_max_m_ = 0.0;
}

// the probe moved on to `fraction_of_step` of its way to the target; the bodies of that substep
void TissueContacts::advance_probe(double fraction_of_step, device::ContactBody* bodies) {
  const ProbePose substep_start = probe_now_;
  probe_now_ = interpolate(probe_step_start_, probe_target_, fraction_of_step);
  make_bodies(substep_start, probe_now_, bodies);
}

void TissueContacts::make_bodies(const ProbePose& from, const ProbePose& to, device::ContactBody* bodies) const {
  device::ContactBody& s = bodies[kSupport];
  s.faces = 1;
  s.face[0] = to_device(support_);
  s.moving = false;
  s.mu_static = params_.support_mu_static;
  s.mu_kinetic = params_.support_mu_kinetic;
  device::ContactBody& p = bodies[kProbe];
  p.faces = static_cast<int>(probe_.faces.size());
  for (int f = 0; f < p.faces; ++f) p.face[f] = to_device(world_face(probe_.faces[f], to));
  p.moving = true;
  p.start_rotation = to_device(from.rotation);
  p.start_position_m = to_device(from.position_m);
  p.end_rotation = to_device(to.rotation);
  p.end_position_m = to_device(to.position_m);
  p.mu_static = params_.probe_mu_static;
  p.mu_kinetic = params_.probe_mu_kinetic;
}

// [soft-tissue, Algorithm 1 lines 6-9] find solid contacts (device::find_contact), the probe where
// it is at the end of this substep
void TissueContacts::begin_substep(pbd::Particles& particles, double h_s, double fraction_of_step) {
  (void)h_s;
  advance_probe(fraction_of_step, bodies_);
  count_ = 0;
  probe_contacts_ = support_contacts_ = 0;
  // a body of another size than the radii were made for: no contacts rather than a read past them
  if (particles.size() != radius_m_.size()) return;
  for (int i = 0; i < particles.size(); ++i) {
    if (!(particles.inv_mass_per_kg[i] > 0.0)) continue;  // pinned, driven or quarantined
    const device::Vec3 x = to_device(particles.position_m.col(i)), xp = to_device(particles.predicted_m.col(i));
    for (int b = kSupport; b <= kProbe; ++b) {
      Contact& c = contacts_[count_];  // two slots per particle: never past the end
      if (!device::find_contact(bodies_[b], x, xp, radius_m_[i], params_.contact_margin_m, &c.slot)) continue;
      c.particle = i;
      c.body = b;
      ++count_;
      ++(b == kProbe ? probe_contacts_ : support_contacts_);
    }
  }
  stabilise(particles);
}

// [soft-tissue, Algorithm 1 lines 10-15] stabilisation (device::stabilise_contact). Sequential
// passes (each particle has at most two contacts, so the paper's averaging dx/n is not needed)
void TissueContacts::stabilise(pbd::Particles& particles) {
  for (int it = 0; it < params_.stabilisation_iterations; ++it) {
    for (int k = 0; k < count_; ++k) {
      const Contact& c = contacts_[k];
      device::Vec3 x = to_device(particles.position_m.col(c.particle));
      device::Vec3 xp = to_device(particles.predicted_m.col(c.particle));
      const double moved = device::stabilise_contact(c.slot, radius_m_[c.particle], &x, &xp);
      if (moved == 0.0) continue;
      particles.position_m.col(c.particle) = Vector3d(x.x, x.y, x.z);
      particles.predicted_m.col(c.particle) = Vector3d(xp.x, xp.y, xp.z);
      stabilisation_max_m_ = std::max(stabilisation_max_m_, moved);
    }
  }
}

// the contact group of [soft-tissue, Algorithm 1 lines 17-21], applied at once (Gauss-Seidel):
// non-penetration, then Coulomb friction on the slip relative to the body
void TissueContacts::project(pbd::Particles& particles, double h_s) {
  (void)h_s;
  for (int k = 0; k < count_; ++k) {
    Contact& c = contacts_[k];
    const device::ContactBody& body = bodies_[c.body];
    device::Vec3 xp = to_device(particles.predicted_m.col(c.particle));
    device::project_contact(&c.slot, radius_m_[c.particle], body.mu_static, body.mu_kinetic,
                            to_device(particles.position_m.col(c.particle)), &xp);
    particles.predicted_m.col(c.particle) = Vector3d(xp.x, xp.y, xp.z);
  }
}

// force on each body (device::contact_force_n), summed over its contacts
void TissueContacts::end_substep(const pbd::Particles& particles, double h_s) {
  device::Vec3 sum[2];
  const double inv_h2 = 1.0 / (h_s * h_s);
  for (int k = 0; k < count_; ++k) {
    const Contact& c = contacts_[k];
    sum[c.body] += device::contact_force_n(c.slot, particles.mass_kg[c.particle], inv_h2);
  }
  ++substeps_seen_;
  probe_force_sum_n_ += Vector3d(sum[kProbe].x, sum[kProbe].y, sum[kProbe].z);
  support_force_sum_n_ += Vector3d(sum[kSupport].x, sum[kSupport].y, sum[kSupport].z);
  probe_force_n_ = probe_force_sum_n_ / substeps_seen_;
  support_force_n_ = support_force_sum_n_ / substeps_seen_;
}

bool TissueContacts::device_setup(DeviceSetup* setup) const {
  setup->radius_m = radius_m_.data();
  setup->particles = static_cast<int>(radius_m_.size());
  setup->bodies = 2;
  setup->margin_m = params_.contact_margin_m;
  setup->stabilisation_iterations = params_.stabilisation_iterations;
  return true;
}

// the same poses begin_substep would take, substep by substep
void TissueContacts::device_bodies(int substeps, device::ContactBody* bodies) {
  for (int s = 0; s < substeps; ++s) advance_probe(static_cast<double>(s + 1) / substeps, bodies + 2 * s);
}

void TissueContacts::device_results(const Vector3d* force_n, const int* contacts, double stabilisation_max_m) {
  support_force_n_ = force_n[kSupport];
  probe_force_n_ = force_n[kProbe];
  support_contacts_ = contacts[kSupport];
  probe_contacts_ = contacts[kProbe];
  stabilisation_max_m_ = stabilisation_max_m;
}

}  // namespace pcisim::physics::soft_tissue
