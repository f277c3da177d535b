#include "anatomy/mesh/triangle_mesh.h"

#include <fstream>
#include <iomanip>
#include <limits>
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

}  // namespace pcisim::anatomy
