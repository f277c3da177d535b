#include "physics/soft_tissue/tissue_body.h"

#include <cmath>
#include <stdexcept>

namespace pcisim::physics::soft_tissue {

namespace {

const TissueParams& validated(const TissueParams& p) {
  validate(p);
  return p;
}

ContactPlane unit_support(const ContactPlane& s) {
  const double len = s.normal.norm();
  if (!s.normal.allFinite() || !(len > 0.0) || !std::isfinite(len) || !std::isfinite(s.offset_m))
    throw std::invalid_argument("soft_tissue: the support needs a finite non-zero normal and a finite offset_m");
  return {s.normal / len, s.offset_m / len};
}

pbd::PbdParams pbd_params(const TissueParams& p) {
  pbd::PbdParams out;
  out.substeps = p.substeps;
  out.iterations = p.iterations;
  out.solver = p.solver;
  out.sor_w = p.sor_w;
  out.gravity_m_per_s2 = p.gravity_m_per_s2;
  out.damping_per_s = p.damping_per_s;
  return out;
}

double particle_mass(const TissueModel& model, const TissueParams& p) {
  const double r = model.spec.particle_radius_m;
  return p.density_kg_per_m3 * r * r * r;
}

}  // namespace

TissueBody::TissueBody(const TissueModel& model, const TissueParams& params, const ContactPlane& support,
                       const ConvexProbe& probe)
    : params_(validated(params)),
      pbd_params_(pbd_params(params)),
      particle_mass_kg_(particle_mass(model, params)),
      rest_m_(model.rest_m),
      contacts_(static_cast<int>(model.rest_m.cols()), params.contact_radius_factor * model.spec.particle_radius_m,
                params, unit_support(support), normalised(probe)) {
  for (int i = 0; i < rest_m_.cols(); ++i) system_.add_particle(rest_m_.col(i), particle_mass_kg_);
  for (const std::vector<int>& members : model.clusters) system_.add_cluster(members, params_.cluster_compliance_s2);
  system_.finalize();
}

// the copy's contacts are its own (PbdSystem is handed them per step, never keeps them)
TissueBody::TissueBody(const TissueBody& other) = default;

bool TissueBody::set_probe_pose(const ProbePose& pose) {
  const double q = pose.rotation.norm();
  if (!pose.position_m.allFinite() || !pose.rotation.coeffs().allFinite() || !(q > 0.0) || !std::isfinite(q))
    return false;
  contacts_.set_probe_target({pose.position_m, pose.rotation.normalized()});
  return true;
}

void TissueBody::step(double dt_s) {
  contacts_.begin_step();
  system_.step(dt_s, pbd_params_, &contacts_);
}

}  // namespace pcisim::physics::soft_tissue
