#pragma once
// The unit cantilever the rod is checked on against the elastica (tests/physics/rod/ and
// pcisim-bench rod): L = 1 m, EI = 1 N m^2, mu = 1 kg/m, clamped at the
// origin along +x, so a tip force of alpha N along -y has load parameter alpha = P L^2 / EI and
// gravity g along -y has w = mu g L^3 / EI = g. EA = GA = 1e7 N: the elastica is inextensible;
// at alpha = 10 the axial and shear strains (1e-6) move the tip by about 1e-4 %.
#include <Eigen/Geometry>

#include "physics/rod/cosserat_rod.h"

namespace pcisim::physics::rod {

inline CosseratRodParams unit_cantilever(int segments) {
  CosseratRodParams p;
  p.length_m = 1.0;
  p.segments = segments;
  p.bending_stiffness_nm2 = 1.0;
  p.torsional_stiffness_nm2 = 0.8;
  p.axial_stiffness_n = 1e7;
  p.shear_stiffness_n = 1e7;
  p.mass_per_length_kg_per_m = 1.0;
  p.outer_diameter_m = 0.01;
  return p;
}

inline Eigen::Quaterniond along_x() {
  return Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX());
}

inline CosseratRod make_unit_cantilever(const CosseratRodParams& p) {
  return CosseratRod(p, Eigen::Vector3d::Zero(), along_x());
}

struct CantileverTip {
  double dv_over_l, dh_over_l, angle_rad;
};

// the tip's deflection in the x-y plane of a unit cantilever bent towards -y
inline CantileverTip cantilever_tip(const CosseratRod& rod) {
  const Eigen::Vector3d p = rod.nodes_m().back();
  const Eigen::Vector3d t = rod.orientations().back() * Eigen::Vector3d::UnitZ();
  return {-p.y(), 1.0 - p.x(), std::atan2(-t.y(), t.x())};
}

}  // namespace pcisim::physics::rod
