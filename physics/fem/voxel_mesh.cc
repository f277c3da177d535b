#include "physics/fem/voxel_mesh.h"

#include <Eigen/LU>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "anatomy/mesh/kuhn_tetrahedra.h"

namespace pcisim::physics::fem {

FemMesh voxel_tet_mesh(const Eigen::Matrix3Xd& voxel_centres_m, double voxel_m) {
  if (voxel_centres_m.cols() == 0 || !(voxel_m > 0.0))
    throw std::invalid_argument("fem: no voxels to mesh (or a voxel size that is not positive)");
  // corners on the grid of the voxels' corners, keyed by integer coordinates from the first one
  const Eigen::Vector3d corner0 = voxel_centres_m.col(0) - Eigen::Vector3d::Constant(0.5 * voxel_m);
  std::map<std::array<long, 3>, int> node_of;
  FemMesh mesh;
  std::vector<Eigen::Vector3d> nodes;
  auto node = [&](const std::array<long, 3>& key) {
    const auto [it, added] = node_of.emplace(key, static_cast<int>(nodes.size()));
    if (added) nodes.push_back(corner0 + voxel_m * Eigen::Vector3d(key[0], key[1], key[2]));
    return it->second;
  };
  for (Eigen::Index v = 0; v < voxel_centres_m.cols(); ++v) {
    const Eigen::Vector3d c = (voxel_centres_m.col(v) - corner0) / voxel_m - Eigen::Vector3d::Constant(0.5);
    const std::array<long, 3> base{std::lround(c.x()), std::lround(c.y()), std::lround(c.z())};
    for (const auto& t : anatomy::kKuhnTetrahedra) {
      std::array<int, 4> tet{};
      for (int k = 0; k < 4; ++k)
        tet[k] = node({base[0] + (t[k] & 1), base[1] + ((t[k] >> 1) & 1), base[2] + ((t[k] >> 2) & 1)});
      mesh.tets.push_back(tet);
    }
  }
  mesh.rest_m.resize(3, static_cast<Eigen::Index>(nodes.size()));
  for (size_t i = 0; i < nodes.size(); ++i) mesh.rest_m.col(static_cast<Eigen::Index>(i)) = nodes[i];
  return mesh;
}

Embedding embed(const FemMesh& mesh, const Eigen::Vector3d& p_m) {
  Embedding best;
  double best_min = -std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < mesh.tets.size(); ++i) {
    const auto& t = mesh.tets[i];
    Eigen::Matrix3d e;
    for (int c = 0; c < 3; ++c) e.col(c) = mesh.rest_m.col(t[c + 1]) - mesh.rest_m.col(t[0]);
    const Eigen::Vector3d l = e.inverse() * (p_m - mesh.rest_m.col(t[0]));
    const Eigen::Vector4d w(1.0 - l.sum(), l.x(), l.y(), l.z());
    if (w.minCoeff() > best_min) {
      best_min = w.minCoeff();
      best.tet = static_cast<int>(i);
      best.weights = w;
    }
  }
  return best;
}

Eigen::Vector3d embedded_position(const FemMesh& mesh, const Eigen::VectorXd& x, const Embedding& e) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) p += e.weights[k] * x.segment<3>(3 * mesh.tets[e.tet][k]);
  return p;
}

}  // namespace pcisim::physics::fem
