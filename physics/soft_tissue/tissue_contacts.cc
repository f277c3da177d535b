#include "physics/soft_tissue/tissue_contacts.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "physics/soft_tissue/contact_rules.h"

namespace pcisim::physics::soft_tissue {

using Eigen::Vector3d;

namespace {

// the tangential part of v on a plane of unit normal n
Vector3d tangential(const Vector3d& v, const Vector3d& n) {
  return v - n.dot(v) * n;
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

void TissueContacts::add_contact(int particle, bool probe, const ContactPlane& plane, const Vector3d& shift_m) {
  if (count_ >= static_cast<int>(contacts_.size())) return;  // never: at most one per body and particle
  Contact& c = contacts_[count_++];
  c.particle = particle;
  c.probe = probe;
  c.plane = plane;
  c.surface_shift_m = shift_m;
  c.normal_m = 0.0;
  c.friction_m.setZero();
}

// [soft-tissue, Algorithm 1 lines 6-9] find solid contacts: a particle whose start or predicted
// position is within the contact distance plus a margin of the support, or of the probe where the
// probe is at the end of this substep (against its face of least penetration)
void TissueContacts::begin_substep(pbd::Particles& particles, double h_s, double fraction_of_step) {
  (void)h_s;
  const ProbePose substep_start = probe_now_;
  probe_now_ = interpolate(probe_step_start_, probe_target_, fraction_of_step);
  count_ = 0;
  probe_contacts_ = support_contacts_ = 0;
  const bool have_probe = !probe_.faces.empty();
  // a body of another size than the radii were made for: no contacts rather than a read past them
  if (particles.size() != radius_m_.size()) return;
  for (int i = 0; i < particles.size(); ++i) {
    if (!(particles.inv_mass_per_kg[i] > 0.0)) continue;  // pinned, driven or quarantined
    const Vector3d x = particles.position_m.col(i), xp = particles.predicted_m.col(i);
    const double radius_m = radius_m_[i], reach_m = radius_m + params_.contact_margin_m;
    if (std::min(plane_gap_m(x, support_, radius_m), plane_gap_m(xp, support_, radius_m)) < params_.contact_margin_m) {
      add_contact(i, false, support_, Vector3d::Zero());
      ++support_contacts_;
    }
    if (!have_probe) continue;
    double d_start = 0.0, d_pred = 0.0;
    // the face is chosen from where the particle starts the substep, against the probe's pose at
    // its end: the probe pushes a particle it has moved onto back out of the side it came from
    const int face = least_penetration_face(probe_.faces, probe_now_, x, &d_start);
    least_penetration_face(probe_.faces, probe_now_, xp, &d_pred);
    if (face < 0 || std::min(d_start, d_pred) >= reach_m) continue;
    // the probe's motion at the particle over the substep, for the relative slip of friction
    const Vector3d local = substep_start.rotation.conjugate() * (x - substep_start.position_m);
    const Vector3d shift = probe_now_.rotation * local + probe_now_.position_m - x;
    add_contact(i, true, world_face(probe_.faces[face], probe_now_), shift);
    ++probe_contacts_;
  }
  stabilise(particles);
}

// [soft-tissue, Algorithm 1 lines 10-15] stabilisation: the contacts are solved on the start
// positions x and the same correction is added to x and x*, so x* - x (the velocity) is unchanged:
// overlap that exists at the start of the substep (a probe moved onto a particle) is removed
// without launching the particle. Sequential passes (each particle has at most two contacts, so
// the paper's averaging dx/n is not needed)
void TissueContacts::stabilise(pbd::Particles& particles) {
  for (int it = 0; it < params_.stabilisation_iterations; ++it) {
    for (int k = 0; k < count_; ++k) {
      const Contact& c = contacts_[k];
      Vector3d x = particles.position_m.col(c.particle);
      const double moved = non_penetration_m(c.plane, radius_m_[c.particle], &x);
      if (moved == 0.0) continue;
      const Vector3d dx = x - particles.position_m.col(c.particle);
      particles.position_m.col(c.particle) = x;
      particles.predicted_m.col(c.particle) += dx;
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
    auto xp = particles.predicted_m.col(c.particle);
    Vector3d x = xp;
    c.normal_m += non_penetration_m(c.plane, radius_m_[c.particle], &x);
    const double mu_s = c.probe ? params_.probe_mu_static : params_.support_mu_static;
    const double mu_k = c.probe ? params_.probe_mu_kinetic : params_.support_mu_kinetic;
    if (c.normal_m > 0.0 && mu_s > 0.0) {
      // slip without friction = the slip now minus what friction already took away
      const Vector3d slip =
          tangential(x - particles.position_m.col(c.particle) - c.surface_shift_m, c.plane.normal) - c.friction_m;
      const Vector3d total = coulomb_friction_m(slip, c.normal_m, mu_s, mu_k);
      x += total - c.friction_m;
      c.friction_m = total;
    }
    xp = x;
  }
}

// force on the body = -(the momentum its contacts gave the particles) / h: a correction dx is a
// velocity change dx / h [soft-tissue eq 6], so F = -sum m dx / h^2 over the substep
void TissueContacts::end_substep(const pbd::Particles& particles, double h_s) {
  Vector3d probe_n = Vector3d::Zero(), support_n = Vector3d::Zero();
  const double inv_h2 = 1.0 / (h_s * h_s);
  for (int k = 0; k < count_; ++k) {
    const Contact& c = contacts_[k];
    const Vector3d f = -particles.mass_kg[c.particle] * inv_h2 * (c.normal_m * c.plane.normal + c.friction_m);
    (c.probe ? probe_n : support_n) += f;
  }
  ++substeps_seen_;
  probe_force_sum_n_ += probe_n;
  support_force_sum_n_ += support_n;
  probe_force_n_ = probe_force_sum_n_ / substeps_seen_;
  support_force_n_ = support_force_sum_n_ / substeps_seen_;
}

}  // namespace pcisim::physics::soft_tissue
