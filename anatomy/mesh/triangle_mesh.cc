#include "anatomy/mesh/triangle_mesh.h"

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace pcisim::anatomy {
namespace {

std::ofstream open_for_writing(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  // enough digits that a metre coordinate reads back to the same double
  out << std::setprecision(std::numeric_limits<double>::max_digits10);
  return out;
}

void finish(std::ofstream& out, const std::string& path) {
  out.flush();
  if (!out) throw std::runtime_error(path + ": write failed");
}

}  // namespace

void write_obj(const TriangleMesh& mesh, const std::string& path) {
  std::ofstream out = open_for_writing(path);
  out << "# pcisim triangle mesh, metres\n";
  for (const auto& v : mesh.vertices_m) out << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  // obj indices are 1-based
  for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  finish(out, path);
}

void write_ply(const TriangleMesh& mesh, const std::string& path) {
  std::ofstream out = open_for_writing(path);
  out << "ply\nformat ascii 1.0\ncomment pcisim triangle mesh, metres\n"
      << "element vertex " << mesh.vertices_m.size() << "\nproperty double x\nproperty double y\n"
      << "property double z\nelement face " << mesh.triangles.size()
      << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : mesh.vertices_m) out << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  for (const auto& t : mesh.triangles) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  finish(out, path);
}

double winding_number(const TriangleMesh& mesh, const Eigen::Vector3d& p_m) {
  // tan(omega / 2) = a . (b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|), a b c the corners
  // seen from p; atan2 keeps the quadrant, so a triangle seen under more than a hemisphere counts
  double omega = 0.0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices_m[t[0]] - p_m, b = mesh.vertices_m[t[1]] - p_m,
                          c = mesh.vertices_m[t[2]] - p_m;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    omega += 2.0 * std::atan2(a.dot(b.cross(c)), den);
  }
  return omega / (4.0 * std::numbers::pi);
}

}  // namespace pcisim::anatomy
