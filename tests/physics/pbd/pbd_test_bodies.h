#pragma once
// Small bodies and checks shared by the PBD tests (header only, no test of its own).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <vector>

#include "physics/pbd/grid_clusters.h"
#include "physics/pbd/pbd_system.h"
#include "physics/pbd/rotation_extraction.h"

namespace pcisim::physics::pbd::testing {

struct BlockSpec {
  int n = 4;  // n x n x n lattice
  double spacing_m = 0.01;
  double mass_kg = 0.001;
  double spring_compliance_m_per_n = 1e-3;
  double cluster_cube_m = 0.02;
  double cluster_overlap = 0.25;
  double cluster_compliance_s2 = 1e-4;
  bool springs = true;
  bool clusters = true;
  bool pin_top = false;  // pin the z = max layer
};

inline int block_index(int n, int i, int j, int k) {
  return (k * n + j) * n + i;
}

// builds without finalizing, so a test can change masses or pin before finalize()
inline PbdSystem block_unfinalized(const BlockSpec& s, std::vector<double> mass_kg = {}) {
  PbdSystem sys;
  const int n = s.n;
  Eigen::Matrix3Xd rest(3, n * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int id = block_index(n, i, j, k);
        rest.col(id) = s.spacing_m * Eigen::Vector3d(i, j, k);
        sys.add_particle(rest.col(id), mass_kg.empty() ? s.mass_kg : mass_kg[id]);
        if (s.pin_top && k == n - 1) sys.pin(id);
      }
  if (s.springs) {
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
          for (int o = 0; o < 3; ++o) {
            int ii = i + (o == 0), jj = j + (o == 1), kk = k + (o == 2);
            if (ii < n && jj < n && kk < n)
              sys.add_distance(block_index(n, i, j, k), block_index(n, ii, jj, kk), s.spring_compliance_m_per_n);
          }
  }
  if (s.clusters)
    for (const auto& c : grid_clusters(rest, s.cluster_cube_m, s.cluster_overlap))
      sys.add_cluster(c, s.cluster_compliance_s2);
  return sys;
}

inline PbdSystem block(const BlockSpec& s) {
  PbdSystem sys = block_unfinalized(s);
  sys.finalize();
  return sys;
}

inline bool all_finite(const PbdSystem& sys) {
  return sys.particles().position_m.allFinite() && sys.particles().velocity_m_per_s.allFinite();
}

inline double max_abs_coordinate_m(const PbdSystem& sys) {
  return sys.particles().position_m.cwiseAbs().maxCoeff();
}

// largest |length - rest| / rest over the distance constraints
inline double max_strain(const PbdSystem& sys) {
  double worst = 0.0;
  for (const auto& c : sys.distance_constraints()) {
    const double len = (sys.particles().position_m.col(c.i) - sys.particles().position_m.col(c.j)).norm();
    worst = std::max(worst, std::abs(len - c.rest_m) / c.rest_m);
  }
  return worst;
}

// largest distance of a particle from the rest shape after the best rigid fit (rest -> now)
inline double shape_error_m(const Eigen::Matrix3Xd& rest_m, const Eigen::Matrix3Xd& x_m) {
  const Eigen::Vector3d c0 = rest_m.rowwise().mean(), c = x_m.rowwise().mean();
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  double moment = 0.0;
  for (int i = 0; i < x_m.cols(); ++i) {
    a += (x_m.col(i) - c) * (rest_m.col(i) - c0).transpose();
    moment += (rest_m.col(i) - c0).squaredNorm();
  }
  const Eigen::Matrix3d r = extract_rotation(a, Eigen::Matrix3d::Identity(), moment);
  double worst = 0.0;
  for (int i = 0; i < x_m.cols(); ++i) worst = std::max(worst, (r * (rest_m.col(i) - c0) + c - x_m.col(i)).norm());
  return worst;
}

inline Eigen::Vector3d linear_momentum(const PbdSystem& sys) {
  const auto& p = sys.particles();
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  for (int i = 0; i < p.size(); ++i) l += p.mass_kg[i] * p.velocity_m_per_s.col(i);
  return l;
}

inline Eigen::Vector3d angular_momentum(const PbdSystem& sys) {
  const auto& p = sys.particles();
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  for (int i = 0; i < p.size(); ++i) l += p.mass_kg[i] * p.position_m.col(i).cross(p.velocity_m_per_s.col(i));
  return l;
}

inline double kinetic_energy_j(const PbdSystem& sys) {
  const auto& p = sys.particles();
  double e = 0.0;
  for (int i = 0; i < p.size(); ++i) e += 0.5 * p.mass_kg[i] * p.velocity_m_per_s.col(i).squaredNorm();
  return e;
}

// springs' elastic energy, sum 0.5 C^2 / alpha (compliant springs only)
inline double spring_energy_j(const PbdSystem& sys) {
  double e = 0.0;
  for (const auto& c : sys.distance_constraints()) {
    if (c.compliance_m_per_n <= 0.0) continue;
    const double len = (sys.particles().position_m.col(c.i) - sys.particles().position_m.col(c.j)).norm();
    e += 0.5 * (len - c.rest_m) * (len - c.rest_m) / c.compliance_m_per_n;
  }
  return e;
}

// clusters' elastic energy, sum 0.5 (m / alpha) |x - g|^2 (compliant clusters only)
inline double cluster_energy_j(const PbdSystem& sys) {
  const auto& p = sys.particles();
  const auto& cl = sys.clusters();
  std::vector<Eigen::Vector3d> goals(cl.max_size());
  double e = 0.0;
  for (int c = 0; c < cl.count(); ++c) {
    if (cl.compliance_s2(c) <= 0.0) continue;
    cl.goals(c, p.position_m, p.mass_kg, goals.data());
    for (int s = cl.begin(c); s < cl.end(c); ++s) {
      const int i = cl.member(s);
      e += 0.5 * p.mass_kg[i] / cl.compliance_s2(c) * (p.position_m.col(i) - goals[s - cl.begin(c)]).squaredNorm();
    }
  }
  return e;
}

inline Eigen::Matrix3d random_rotation(int seed) {
  std::srand(seed);
  Eigen::Quaterniond q(Eigen::Vector4d::Random());
  return q.normalized().toRotationMatrix();
}

}  // namespace pcisim::physics::pbd::testing
