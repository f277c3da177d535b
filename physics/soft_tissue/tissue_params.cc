#include "physics/soft_tissue/tissue_params.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace pcisim::physics::soft_tissue {
namespace {

void require(bool ok, const char* field, const char* range) {
  if (!ok) throw std::invalid_argument(std::string("soft_tissue: ") + field + " must be in " + range);
}

bool within(double v, double lo, double hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

}  // namespace

void validate(const TissueParams& p) {
  require(within(p.density_kg_per_m3, 0.0, 1e5) && p.density_kg_per_m3 > 0.0, "density_kg_per_m3", "(0, 1e5]");
  require(within(p.cluster_compliance_s2, 0.0, 1.0), "cluster_compliance_s2", "[0, 1]");
  require(p.substeps >= 1 && p.substeps <= 100, "substeps", "[1, 100]");
  require(p.iterations >= 1 && p.iterations <= 1000, "iterations", "[1, 1000]");
  require(p.solver == pbd::SolverKind::kGaussSeidel || p.solver == pbd::SolverKind::kJacobi, "solver",
          "{kGaussSeidel, kJacobi}");
  require(within(p.sor_w, 1.0, 2.0), "sor_w", "[1, 2]");
  require(p.stabilisation_iterations >= 0 && p.stabilisation_iterations <= 100, "stabilisation_iterations", "[0, 100]");
  require(within(p.damping_per_s, 0.0, 1000.0), "damping_per_s", "[0, 1000]");
  require(p.gravity_m_per_s2.allFinite(), "gravity_m_per_s2", "finite values");
  require(within(p.contact_radius_factor, 0.0, 2.0), "contact_radius_factor", "[0, 2]");
  require(within(p.contact_margin_m, 0.0, 0.1), "contact_margin_m", "[0, 0.1]");
  require(within(p.support_mu_static, 0.0, 10.0), "support_mu_static", "[0, 10]");
  require(within(p.support_mu_kinetic, 0.0, p.support_mu_static), "support_mu_kinetic", "[0, support_mu_static]");
  require(within(p.probe_mu_static, 0.0, 10.0), "probe_mu_static", "[0, 10]");
  require(within(p.probe_mu_kinetic, 0.0, p.probe_mu_static), "probe_mu_kinetic", "[0, probe_mu_static]");
}

}  // namespace pcisim::physics::soft_tissue
