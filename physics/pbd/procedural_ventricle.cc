#include "physics/pbd/procedural_ventricle.h"

#include <cmath>
#include <stdexcept>

#include "physics/pbd/grid_clusters.h"

namespace pcisim::physics::pbd {

namespace {
// inside an ellipsoid with equatorial semi-axis r and long semi-axis l
bool inside(const Eigen::Vector3d& p, double r, double l) {
  return (p.x() * p.x() + p.y() * p.y()) / (r * r) + p.z() * p.z() / (l * l) <= 1.0;
}
}  // namespace

Ventricle build_ventricle(const VentricleSpec& s) {
  if (!(s.spacing_m > 0.0) || !(s.wall_m > 0.0) || s.wall_m >= s.radius_m)
    throw std::invalid_argument("ventricle: spacing > 0 and 0 < wall < radius");
  Ventricle v;
  const int nx = static_cast<int>(std::ceil(s.radius_m / s.spacing_m));
  const int nz = static_cast<int>(std::ceil(s.half_length_m / s.spacing_m));
  const int dim_x = 2 * nx + 1, dim_z = 2 * nz + 1;
  std::vector<int> lattice(static_cast<size_t>(dim_x) * dim_x * dim_z, -1);
  auto at = [&](int i, int j, int k) -> int& { return lattice[(static_cast<size_t>(k) * dim_x + j) * dim_x + i]; };
  const double mass_kg = s.density_kg_per_m3 * s.spacing_m * s.spacing_m * s.spacing_m;
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < dim_z; ++k)
    for (int j = 0; j < dim_x; ++j)
      for (int i = 0; i < dim_x; ++i) {
        const Eigen::Vector3d p = s.spacing_m * Eigen::Vector3d(i - nx, j - nx, k - nz);
        if (p.z() > s.base_z_m || !inside(p, s.radius_m, s.half_length_m) ||
            inside(p, s.radius_m - s.wall_m, s.half_length_m - s.wall_m))
          continue;
        at(i, j, k) = v.system.add_particle(p, mass_kg);
        points.push_back(p);
      }
  // springs to face and edge neighbours (each pair once)
  const int offsets[9][3] = {{1, 0, 0}, {0, 1, 0},  {0, 0, 1}, {1, 1, 0}, {1, -1, 0},
                             {1, 0, 1}, {1, 0, -1}, {0, 1, 1}, {0, 1, -1}};
  for (int k = 0; k < dim_z; ++k)
    for (int j = 0; j < dim_x; ++j)
      for (int i = 0; i < dim_x; ++i) {
        const int a = at(i, j, k);
        if (a < 0) continue;
        for (const auto& o : offsets) {
          const int ii = i + o[0], jj = j + o[1], kk = k + o[2];
          if (ii < 0 || jj < 0 || kk < 0 || ii >= dim_x || jj >= dim_x || kk >= dim_z) continue;
          if (const int b = at(ii, jj, kk); b >= 0) v.system.add_distance(a, b, s.spring_compliance_m_per_n);
        }
      }
  v.rest_m.resize(3, static_cast<Eigen::Index>(points.size()));
  for (size_t i = 0; i < points.size(); ++i) v.rest_m.col(static_cast<Eigen::Index>(i)) = points[i];
  for (const auto& c : grid_clusters(v.rest_m, s.cluster_cube_m, s.cluster_overlap))
    v.system.add_cluster(c, s.cluster_compliance_s2);
  for (int i = 0; i < v.rest_m.cols(); ++i)
    if (v.rest_m(0, i) < s.septum_x_m) {
      v.system.drive(i);
      v.driven.push_back(i);
    }
  v.system.finalize();
  return v;
}

}  // namespace pcisim::physics::pbd
