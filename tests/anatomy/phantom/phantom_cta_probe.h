#pragma once
// Reading a phantom CTA back in tests: HU at a physical point, a branch of the truth by name, arc
// lengths, landmarks (tests/anatomy/phantom/phantom_cta_test.cc and phantom_cta_family_test.cc).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "anatomy/phantom/phantom_cta.h"

namespace pcisim::anatomy {

inline bool in_grid(const Volume& v, const Eigen::Vector3d& ijk) {
  for (int a = 0; a < 3; ++a) {
    if (!(ijk[a] >= -1e-6 && ijk[a] <= v.dims[a] - 1 + 1e-6)) return false;
  }
  return true;
}

// trilinear HU at a physical point (mm); the point must lie inside the grid
inline double hu_at(const Volume& v, const Eigen::Vector3d& p_mm) {
  const Eigen::Vector3d ijk = v.physical_to_index(p_mm);
  EXPECT_TRUE(in_grid(v, ijk)) << p_mm.transpose();
  int64_t i0[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double x = std::clamp(ijk[a], 0.0, static_cast<double>(v.dims[a] - 1));
    i0[a] = std::min<int64_t>(static_cast<int64_t>(std::floor(x)), v.dims[a] - 2);
    f[a] = x - i0[a];
  }
  double sum = 0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
    sum += w * v.hu(i0[0] + dx, i0[1] + dy, i0[2] + dz);
  }
  return sum;
}

inline const VesselBranch& branch(const PhantomCta& c, const std::string& name) {
  const int b = c.truth.find(name);
  if (b < 0) throw std::runtime_error("no branch " + name);
  return c.truth.branches[b];
}

inline std::vector<double> arcs_mm(const VesselBranch& b) {
  std::vector<double> s(b.points.size(), 0.0);
  for (size_t i = 1; i < s.size(); ++i)
    s[i] = s[i - 1] + 1e3 * (b.points[i].position_m - b.points[i - 1].position_m).norm();
  return s;
}

inline Eigen::Vector3d landmark_mm(const PhantomCta& c, const std::string& name) {
  for (const auto& l : c.landmarks) {
    if (l.name == name) return l.position_m * 1e3;
  }
  ADD_FAILURE() << "no landmark " << name;
  return Eigen::Vector3d::Zero();
}

}  // namespace pcisim::anatomy
