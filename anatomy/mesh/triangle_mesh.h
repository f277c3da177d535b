#pragma once
// An indexed triangle mesh in metres, counter-clockwise faces seen from outside.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace pcisim::anatomy {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices_m;
  std::vector<std::array<int, 3>> triangles;
};

// writes the mesh; throws std::runtime_error naming the path when it cannot
void write_obj(const TriangleMesh& mesh, const std::string& path);
void write_ply(const TriangleMesh& mesh, const std::string& path);

}  // namespace pcisim::anatomy
