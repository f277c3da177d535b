#include "physics/pbd/grid_clusters.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace pcisim::physics::pbd {

std::vector<std::vector<int>> grid_clusters(const Eigen::Matrix3Xd& x_m, double cube_m, double overlap,
                                            int min_members) {
  if (!(cube_m > 0.0) || !(overlap >= 0.0)) throw std::invalid_argument("grid_clusters: cube > 0, overlap >= 0");
  std::vector<std::vector<int>> clusters;
  const int n = static_cast<int>(x_m.cols());
  if (n == 0) return clusters;
  const Eigen::Vector3d lo = x_m.rowwise().minCoeff(), hi = x_m.rowwise().maxCoeff();
  const Eigen::Vector3d span_cells = ((hi - lo) / cube_m).array().floor() + 1.0;
  if (!span_cells.allFinite() || span_cells.prod() > 1e6)
    throw std::invalid_argument("grid_clusters: a " + std::to_string(cube_m) +
                                " m cube makes more than a million cells over these particles");
  const Eigen::Vector3i cells = span_cells.cast<int>();
  const double half = 0.5 * cube_m + overlap * cube_m;
  std::vector<Eigen::Vector3d> centres;
  for (int a = 0; a < cells.x(); ++a)
    for (int b = 0; b < cells.y(); ++b)
      for (int c = 0; c < cells.z(); ++c) {
        const Eigen::Vector3d centre = lo + cube_m * Eigen::Vector3d(a + 0.5, b + 0.5, c + 0.5);
        std::vector<int> members;
        for (int i = 0; i < n; ++i)
          if (((x_m.col(i) - centre).cwiseAbs().array() <= half).all()) members.push_back(i);
        if (static_cast<int>(members.size()) < std::max(min_members, 1)) continue;
        clusters.push_back(std::move(members));
        centres.push_back(centre);
      }
  std::vector<char> covered(n, 0);
  for (const auto& c : clusters)
    for (int i : c) covered[i] = 1;
  if (clusters.empty()) {
    // too few particles for any cube: one global cluster
    std::vector<int> all(n);
    for (int i = 0; i < n; ++i) all[i] = i;
    clusters.push_back(std::move(all));
    return clusters;
  }
  for (int i = 0; i < n; ++i) {
    if (covered[i]) continue;
    size_t best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    for (size_t c = 0; c < centres.size(); ++c) {
      const double d = (x_m.col(i) - centres[c]).squaredNorm();
      if (d < best_d) best_d = d, best = c;
    }
    clusters[best].push_back(i);
  }
  return clusters;
}

}  // namespace pcisim::physics::pbd
