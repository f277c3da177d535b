#include "bench/kidney_tetgen_mesh.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "anatomy/heart/heart_mesh.h"

namespace pcisim::bench {

physics::fem::FemMesh kidney_tetgen_mesh(const anatomy::KidneySpec& spec, double spacing_m) {
  namespace fs = std::filesystem;
  anatomy::KidneySpec coarse = spec;
  const double h_mm = spacing_m * 1e3;
  coarse.surface_segments = std::max(16, static_cast<int>(std::lround(150.0 / h_mm)));  // ~150 mm round
  coarse.surface_rings = std::max(8, static_cast<int>(std::lround(125.0 / h_mm)));      // ~125 mm pole to pole
  const anatomy::TriangleMesh surface = anatomy::make_kidney_phantom(coarse).surface;

  // the surface as OFF in millimetres, TetGen run in a folder of its own
  const fs::path dir = fs::temp_directory_path() / fmt::format("pcisim-tetgen-{}", ::getpid());
  fs::create_directories(dir);
  struct RemoveWhenDone {
    fs::path dir;
    ~RemoveWhenDone() {
      std::error_code ignored;
      fs::remove_all(dir, ignored);
    }
  } cleanup{dir};
  {
    std::ofstream off(dir / "organ.off");
    off.precision(17);
    off << "OFF\n" << surface.vertices_m.size() << " " << surface.triangles.size() << " 0\n";
    for (const Eigen::Vector3d& v : surface.vertices_m)
      off << v.x() * 1e3 << " " << v.y() * 1e3 << " " << v.z() * 1e3 << "\n";
    for (const auto& t : surface.triangles) off << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
    if (!off) throw std::runtime_error("tetgen: cannot write " + (dir / "organ.off").string());
  }
  // p: a piecewise linear complex, z: indices from 0, q1.4: radius-edge ratio, a: volume bound, Q: quiet
  const std::string cmd = fmt::format("cd '{}' && tetgen -pzq1.4a{:.4f}Q organ.off > tetgen.log 2>&1", dir.string(),
                                      h_mm * h_mm * h_mm / (6.0 * std::sqrt(2.0)));
  if (std::system(cmd.c_str()) != 0) {
    std::ifstream log(dir / "tetgen.log");
    const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
    throw std::runtime_error("tetgen failed on the kidney's surface (installed? scripts/setup):\n" + text);
  }
  const anatomy::HeartMesh m = anatomy::read_tetgen_mesh((dir / "organ.1").string());
  return {m.vertices_m, m.tets};
}

}  // namespace pcisim::bench
