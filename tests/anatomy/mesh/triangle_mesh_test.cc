#include "anatomy/mesh/triangle_mesh.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace pcisim::anatomy {
namespace {

TriangleMesh tetrahedron() {
  TriangleMesh m;
  m.vertices_m = {{0, 0, 0}, {1e-3, 0, 0}, {0, 1e-3, 0}, {0, 0, 1.0 / 3.0}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

std::string read_all(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string temp(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("pcisim_tm_" + std::to_string(::getpid()) + name)).string();
}

TEST(TriangleMeshTest, ObjHasOneBasedFacesAndExactCoordinates) {
  const std::string path = temp(".obj");
  write_obj(tetrahedron(), path);
  std::istringstream in(read_all(path));
  std::filesystem::remove(path);
  std::string line;
  int v = 0, f = 0;
  double last_z = 0;
  while (std::getline(in, line)) {
    std::istringstream l(line);
    std::string tag;
    l >> tag;
    if (tag == "v") {
      double x, y, z;
      l >> x >> y >> z;
      last_z = z;
      ++v;
    } else if (tag == "f") {
      int a, b, c;
      l >> a >> b >> c;
      EXPECT_GE(std::min({a, b, c}), 1);
      EXPECT_LE(std::max({a, b, c}), 4);
      ++f;
    }
  }
  EXPECT_EQ(v, 4);
  EXPECT_EQ(f, 4);
  EXPECT_EQ(last_z, 1.0 / 3.0) << "coordinates must read back to the same double";
}

TEST(TriangleMeshTest, PlyHeaderCountsMatch) {
  const std::string path = temp(".ply");
  write_ply(tetrahedron(), path);
  const std::string text = read_all(path);
  std::filesystem::remove(path);
  EXPECT_EQ(text.rfind("ply\nformat ascii 1.0\n", 0), 0u);
  EXPECT_NE(text.find("element vertex 4\n"), std::string::npos);
  EXPECT_NE(text.find("element face 4\n"), std::string::npos);
  EXPECT_NE(text.find("\n3 1 2 3\n"), std::string::npos);
}

TEST(TriangleMeshTest, UnwritablePathThrowsNamingIt) {
  for (auto* write : {&write_obj, &write_ply}) {
    try {
      write(tetrahedron(), "/nonexistent-dir/mesh.out");
      ADD_FAILURE() << "expected a throw";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/mesh.out"), std::string::npos) << e.what();
    }
  }
}

// the winding number tells inside from outside exactly, even beside a sliver of a face (this
// tetrahedron is 1 mm wide and 333 mm tall) and inside the bounding box's empty corner
TEST(TriangleMeshTest, WindingNumberIsOneInsideZeroOutsideAndMinusOneWoundInsideOut) {
  TriangleMesh m = tetrahedron();
  const Eigen::Vector3d inside(1e-4, 1e-4, 0.2), outside_in_box(0.9e-3, 0.9e-3, 0.2), far(0.5, -0.2, 0.1);
  EXPECT_NEAR(winding_number(m, inside), 1.0, 1e-9);
  EXPECT_NEAR(winding_number(m, outside_in_box), 0.0, 1e-9);
  EXPECT_NEAR(winding_number(m, far), 0.0, 1e-9);
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  EXPECT_NEAR(winding_number(m, inside), -1.0, 1e-9);
}

}  // namespace
}  // namespace pcisim::anatomy
