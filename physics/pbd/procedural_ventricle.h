#pragma once
// A stand-in for the heart until it exists: a thick-walled, truncated ellipsoidal "ventricle"
// sampled on a cubic lattice, lattice springs (face and edge neighbours) plus overlapping
// shape-matching clusters; the septal side is driven.
#include <Eigen/Core>
#include <vector>

#include "physics/pbd/pbd_system.h"

namespace pcisim::physics::pbd {

struct VentricleSpec {
  // roughly a left ventricle at end-diastole
  double radius_m = 0.030;       // outer equatorial semi-axis
  double half_length_m = 0.050;  // outer long semi-axis (z)
  double wall_m = 0.010;         // wall thickness
  double base_z_m = 0.020;       // cut off above this (the base)
  double spacing_m = 0.003;      // lattice spacing
  double density_kg_per_m3 = 1050.0;
  double spring_compliance_m_per_n = 2e-3;
  double cluster_cube_m = 0.012;  // cluster size
  double cluster_overlap = 0.25;  // of the cube edge, on each side
  double cluster_compliance_s2 = 1e-4;
  double septum_x_m = -0.015;  // particles with x below this are driven
};

struct Ventricle {
  PbdSystem system;
  std::vector<int> driven;  // particle indices that follow the prescribed motion
  Eigen::Matrix3Xd rest_m;
};

// builds and finalizes
Ventricle build_ventricle(const VentricleSpec& spec);

}  // namespace pcisim::physics::pbd
