#pragma once
// The kidney's tissue pressed by a probe without physics (this layer has none): a Kuhn tet grid
// over the procedural kidney, its vertices pushed along the beam, most under the probe. For
// pcisim-us-kidney and the CUDA twin's test (a deformation both renderers read the same way).
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>

#include "anatomy/mesh/kuhn_tetrahedra.h"
#include "anatomy/organ/kidney_phantom.h"
#include "ultrasound/mapping/tet_snapshot.h"

namespace pcisim::ultrasound::tools {

// Kuhn cubes of edge h over the kidney's box, a tet kept when its centroid is in the organ
inline TetSnapshot kidney_tets(const anatomy::KidneySpec& spec, double h) {
  const Eigen::Vector3d lo = -spec.semi_axes_mm - Eigen::Vector3d::Constant(h);
  Eigen::Vector3i n;
  for (int k = 0; k < 3; ++k) n[k] = static_cast<int>(std::ceil(2.0 * (spec.semi_axes_mm[k] + h) / h));
  auto id = [&](int i, int j, int k) { return i + (n[0] + 1) * (j + (n[1] + 1) * k); };
  TetSnapshot m;
  m.rest_mm.resize(3, (n[0] + 1) * (n[1] + 1) * (n[2] + 1));
  for (int k = 0; k <= n[2]; ++k)
    for (int j = 0; j <= n[1]; ++j)
      for (int i = 0; i <= n[0]; ++i) m.rest_mm.col(id(i, j, k)) = lo + h * Eigen::Vector3d(i, j, k);
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        for (const auto& t : anatomy::kKuhnTetrahedra) {
          std::array<int, 4> tet;
          Eigen::Vector3d c = Eigen::Vector3d::Zero();
          for (int v = 0; v < 4; ++v) {
            tet[v] = id(i + (t[v] & 1), j + ((t[v] >> 1) & 1), k + ((t[v] >> 2) & 1));
            c += 0.25 * m.rest_mm.col(tet[v]);
          }
          if (anatomy::kidney_normalised_radius(spec, c) < 1.0) m.tets.push_back(tet);
        }
  m.current_mm = m.rest_mm;
  return m;
}

// the probe presses the anterior face (-y) by push_mm under it, fading with lateral distance
// (Gaussian, 20 mm) and to nothing at the posterior face: y' = y + push g(x, z) (y_back - y) / (2 a_y)
inline void press(TetSnapshot& m, double push_mm, double a_y) {
  for (int v = 0; v < m.rest_mm.cols(); ++v) {
    const Eigen::Vector3d r = m.rest_mm.col(v);
    const double g = std::exp(-(r.x() * r.x() + r.z() * r.z()) / (2.0 * 20.0 * 20.0));
    m.current_mm.col(v) =
        r + Eigen::Vector3d(0.0, push_mm * g * std::clamp((a_y - r.y()) / (2.0 * a_y), 0.0, 1.0), 0.0);
  }
}

}  // namespace pcisim::ultrasound::tools
