#include "physics/soft_tissue/tissue_params.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace pcisim::physics::soft_tissue {
namespace {

void require(bool ok, const char* field, const std::string& range) {
  if (!ok) throw std::invalid_argument(std::string("soft_tissue: ") + field + " must be in " + range);
}

}  // namespace

void validate(const TissueParams& p) {
  auto check = [](double v, const ParamRange& range, const char* field) {
    require(range.contains(v), field, range.describe());
  };
  check(p.density_kg_per_m3, kTissueDensityKgPerM3, "density_kg_per_m3");
  check(p.cluster_compliance_s2, kTissueClusterComplianceS2, "cluster_compliance_s2");
  check(p.bulk_modulus_pa, kTissueBulkModulusPa, "bulk_modulus_pa");
  check(p.substeps, kTissueSubsteps, "substeps");
  check(p.iterations, kTissueIterations, "iterations");
  require(p.solver == pbd::SolverKind::kGaussSeidel || p.solver == pbd::SolverKind::kJacobi ||
              p.solver == pbd::SolverKind::kJacobiCuda,
          "solver", "{kGaussSeidel, kJacobi, kJacobiCuda}");
  check(p.sor_w, kTissueSorW, "sor_w");
  check(p.stabilisation_iterations, kTissueStabilisationIterations, "stabilisation_iterations");
  check(p.damping_per_s, kTissueDampingPerS, "damping_per_s");
  require(p.gravity_m_per_s2.allFinite(), "gravity_m_per_s2", "finite values");
  check(p.contact_radius_factor, kTissueContactRadiusFactor, "contact_radius_factor");
  check(p.contact_margin_m, kTissueContactMarginM, "contact_margin_m");
  check(p.support_mu_static, kTissueFriction, "support_mu_static");
  require(in(p.support_mu_kinetic, 0.0, p.support_mu_static), "support_mu_kinetic", "[0, support_mu_static]");
  check(p.probe_mu_static, kTissueFriction, "probe_mu_static");
  require(in(p.probe_mu_kinetic, 0.0, p.probe_mu_static), "probe_mu_kinetic", "[0, probe_mu_static]");
}

}  // namespace pcisim::physics::soft_tissue
