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

// the winding number of the surface about p: the triangles' signed solid angles seen from p over
// 4 pi (Van Oosterom and Strackee, IEEE Trans. Biomed. Eng. 1983). For a closed surface wound
// counter-clockwise seen from outside: 1 inside, 0 outside (exact up to rounding, whatever the
// shape; undefined on the surface itself)
double winding_number(const TriangleMesh& mesh, const Eigen::Vector3d& p_m);

}  // namespace pcisim::anatomy
