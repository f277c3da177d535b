#include "physics/soft_tissue/tissue_body.h"

#include <cmath>
#include <stdexcept>
#include <vector>

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

// each particle's contact distance (TissueParams::contact_surface)
Eigen::VectorXd contact_radii(const TissueModel& model, const TissueParams& p) {
  const double sphere_m = p.contact_radius_factor * model.spec.particle_radius_m;
  Eigen::VectorXd r = Eigen::VectorXd::Constant(model.rest_m.cols(), sphere_m);
  // kSkin: each sphere reaches the skin exactly (the depth, at most the particle radius)
  if (p.contact_surface == ContactSurface::kSkin) {
    if (model.skin_depth_m.size() != r.size())
      throw std::invalid_argument(
          "soft_tissue: contact_surface skin needs the model's skin depths (build_tissue_model)");
    r = model.skin_depth_m;
  }
  return r;
}

}  // namespace

TissueBody::TissueBody(const TissueModel& model, const TissueParams& params, const ContactPlane& support,
                       const ConvexProbe& probe)
    : params_(validated(params)),
      pbd_params_(pbd_params(params)),
      particle_mass_kg_(particle_mass(model, params)),
      rest_m_(model.rest_m),
      contacts_(contact_radii(model, params), params, unit_support(support), normalised(probe)) {
  for (int i = 0; i < rest_m_.cols(); ++i) system_.add_particle(rest_m_.col(i), particle_mass_kg_);
  // each cluster's share of the volume: its particles' cubes (m / density), each split among the
  // clusters that hold it, so that the shares add up to the organ
  std::vector<int> clusters_of(static_cast<size_t>(rest_m_.cols()), 0);
  for (const std::vector<int>& members : model.clusters)
    for (int i : members) ++clusters_of[static_cast<size_t>(i)];
  const double cube_m3 = particle_mass_kg_ / params_.density_kg_per_m3;
  for (const std::vector<int>& members : model.clusters) {
    double volume_m3 = 0.0;
    for (int i : members) volume_m3 += cube_m3 / clusters_of[static_cast<size_t>(i)];
    const double volume_compliance = params_.bulk_modulus_pa > 0.0 ? 1.0 / (params_.bulk_modulus_pa * volume_m3) : -1.0;
    system_.add_cluster(members, params_.cluster_compliance_s2, volume_compliance);
  }
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
