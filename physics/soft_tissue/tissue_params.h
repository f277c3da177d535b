#pragma once
// Parameters of the tissue solver (TissueBody): mass, cluster stiffness, the PBD loop's knobs
// and the contact rules. Defaults follow the paper's FleX settings [soft-tissue, Table 1] where
// it gives them; ranges after each field. validate() names the first field out of range.
#include <Eigen/Core>

#include "physics/param_checks.h"
#include "physics/pbd/pbd_params.h"

namespace pcisim::physics::soft_tissue {

// where the organ meets the support and the probe (TissueParams::contact_surface)
enum class ContactSurface {
  // each particle is a sphere of contact_radius_factor x the particle radius: the paper's
  // particle collisions. A particle sampled just under the skin pokes out of the organ by up to
  // half a radius, so the probe meets the tissue that much before it reaches the skin
  kSpheres,
  // each particle's sphere reaches the organ's surface at rest: its radius is the particle's
  // rest depth under the skin (at most the particle radius; contact_radius_factor is not used),
  // so the contact is the organ's own skin, as a mesh-based reference (the calibration's FEM) has it
  kSkin,
};

struct TissueParams {
  // each particle stands for a cube of edge = the model's particle radius (the sampling
  // spacing): m = density r^3 (the kidney's particles then weigh its volume within ~10 %)
  double density_kg_per_m3 = 1050.0;  // tissue, [soft-tissue, Table 1: 1.05 g/cm3]; (0, 1e5]
  // shape matching compliance = 1 / omega^2 of each cluster's pull (pbd/shape_matching_clusters.h);
  // 0 = rigid clusters. Not calibrated (issue #16 item 6): 2e-5 gives 1.7 N for a 12 mm press of
  // a 20 x 40 mm face at 3.3 mm particles. [0, 1]
  double cluster_compliance_s2 = 2.0e-5;
  // resistance to volume change: each cluster's volume (det F - 1, pbd/shape_matching_clusters.h)
  // with compliance 1 / (K V_c), V_c the cluster's share of the organ's volume. Shape matching
  // alone lets a cluster shrink as easily as it shears (no Poisson effect); a kidney is nearly
  // incompressible [soft-tissue, Discussion, after Miller et al.]. 0 = no volume constraint. [0, 1e9]
  double bulk_modulus_pa = 0.0;
  int substeps = 3;    // [soft-tissue, Table 1]; [1, 100]
  int iterations = 9;  // solver passes per substep [soft-tissue, Table 1]; [1, 1000]
  // Gauss-Seidel, or Jacobi with SOR [soft-tissue eq 7] (the paper: "local" relaxation, factor 1);
  // the contacts are one more group, applied at once. kJacobiCuda: the Jacobi step with its
  // contacts and volumes on a CUDA device (pbd_cuda_solver.h; its CPU twin is kJacobi)
  pbd::SolverKind solver = pbd::SolverKind::kGaussSeidel;
  double sor_w = 1.0;                                // [1, 2]
  int stabilisation_iterations = 1;                  // Algorithm 1 lines 10-15; [0, 100]
  double damping_per_s = 12.0;                       // velocity drag [soft-tissue, Table 1 "damping factor"]; [0, 1000]
  Eigen::Vector3d gravity_m_per_s2{0.0, 9.81, 0.0};  // LPS: a supine patient's posterior (+y) is down; finite
  // contact distance of a particle = factor x the model's particle radius: 0.5 puts the spheres of
  // neighbouring particles (spaced ~r) face to face, so the organ's skin touches. [0, 2]
  double contact_radius_factor = 0.5;
  ContactSurface contact_surface = ContactSurface::kSpheres;
  double contact_margin_m = 2.0e-3;  // a particle this far beyond contact is still a candidate; [0, 0.1]
  // Coulomb friction [soft-tissue, Table 1: shape friction 0.35]; kinetic <= static. [0, 10]
  double support_mu_static = 0.35;
  double support_mu_kinetic = 0.35;
  double probe_mu_static = 0.35;
  double probe_mu_kinetic = 0.35;
};

// the ranges above, once: validate() and the scene loader (effects.soft_tissue) both use them
inline constexpr ParamRange kTissueDensityKgPerM3{1.0, 1e5};
inline constexpr ParamRange kTissueClusterComplianceS2{0.0, 1.0};
inline constexpr ParamRange kTissueBulkModulusPa{0.0, 1e9};
inline constexpr ParamRange kTissueSubsteps{1, 100};
inline constexpr ParamRange kTissueIterations{1, 1000};
inline constexpr ParamRange kTissueSorW{1.0, 2.0};
inline constexpr ParamRange kTissueStabilisationIterations{0, 100};
inline constexpr ParamRange kTissueDampingPerS{0.0, 1000.0};
inline constexpr ParamRange kTissueContactRadiusFactor{0.0, 2.0};
inline constexpr ParamRange kTissueContactMarginM{0.0, 0.1};
inline constexpr ParamRange kTissueFriction{0.0, 10.0};

// throws std::invalid_argument naming the first field out of range and its range
void validate(const TissueParams& params);

}  // namespace pcisim::physics::soft_tissue
