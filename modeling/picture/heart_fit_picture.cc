#include "modeling/picture/heart_fit_picture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "anatomy/heart/template_heart_surface.h"
#include "modeling/picture/tiny_font.h"
#include "png/png_gray.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

// a slice: the plane's normal axis, and the LPS axes shown across and down (+1: increasing to the
// right / downward)
struct Slice {
  const char* name;
  int normal, ax_x, ax_y;
  double sign_x, sign_y;
};

}  // namespace

void write_heart_fit_picture(const anatomy::Volume& ct, const anatomy::HeartMesh& mesh, const anatomy::HeartPose& pose,
                             const Eigen::Matrix3Xd& placed_m, const Eigen::Matrix3Xd& fitted_m,
                             const std::string& title, const std::string& png_path) {
  const Slice slices[3] = {{"CORONAL", 1, 0, 2, +1, -1}, {"SAGITTAL", 0, 1, 2, +1, -1}, {"AXIAL", 2, 0, 1, +1, +1}};
  const Vector3d centre = 1e3 * pose.translation_m;
  const double half_mm = 80, px_mm = 0.5;
  const int side = static_cast<int>(2 * half_mm / px_mm), header = 24, gap = 8;
  const int width = 3 * side + 4 * gap, height = header + side + gap;
  std::vector<uint8_t> rgb(static_cast<size_t>(width) * height * 3, 0);

  // the point under pixel (x, y) of slice s, and back
  auto point = [&](const Slice& s, int x, int y) {
    Vector3d p = centre;
    const double fx = s.sign_x > 0 ? x : side - 1 - x, fy = s.sign_y > 0 ? y : side - 1 - y;
    p[s.ax_x] += (fx + 0.5) * px_mm - half_mm;
    p[s.ax_y] += (fy + 0.5) * px_mm - half_mm;
    return p;
  };
  auto pixel = [&](const Slice& s, const Vector3d& p, int* x, int* y) {
    const double fx = (p[s.ax_x] - centre[s.ax_x] + half_mm) / px_mm - 0.5;
    const double fy = (p[s.ax_y] - centre[s.ax_y] + half_mm) / px_mm - 0.5;
    *x = static_cast<int>(std::lround(s.sign_x > 0 ? fx : side - 1 - fx));
    *y = static_cast<int>(std::lround(s.sign_y > 0 ? fy : side - 1 - fy));
    return *x >= 0 && *y >= 0 && *x < side && *y < side;
  };
  auto put = [&](int v, int x, int y, const uint8_t c[3]) {
    uint8_t* p = rgb.data() + (static_cast<size_t>(header + y) * width + gap + v * (side + gap) + x) * 3;
    p[0] = c[0], p[1] = c[1], p[2] = c[2];
  };

  for (int v = 0; v < 3; ++v) {
    const Slice& s = slices[v];
    // the CT, nearest voxel, window -200..400 HU (fat dark, myocardium grey, contrast white)
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) {
        const Vector3d c = ct.physical_to_index(point(s, x, y));
        const int64_t i = std::llround(c.x()), j = std::llround(c.y()), k = std::llround(c.z());
        uint8_t g = 0;
        if (i >= 0 && j >= 0 && k >= 0 && i < ct.dims[0] && j < ct.dims[1] && k < ct.dims[2])
          g = static_cast<uint8_t>(std::clamp((ct.hu(i, j, k) + 200.0) / 600.0 * 255.0, 0.0, 255.0));
        const uint8_t grey[3] = {g, g, g};
        put(v, x, y, grey);
      }
    // the epicardium cut by the plane: each triangle crossing it gives a segment
    const uint8_t red[3] = {255, 70, 70}, green[3] = {70, 255, 90};
    for (const auto& [verts, colour] : {std::pair{&placed_m, red}, std::pair{&fitted_m, green}}) {
      for (size_t f = 0; f < mesh.faces.size(); ++f) {
        if (mesh.face_markers[f] != anatomy::kEpicardium) continue;
        std::array<Vector3d, 3> q;
        for (int c = 0; c < 3; ++c) q[c] = 1e3 * pose.to_case(verts->col(mesh.faces[f][c]));
        std::vector<Vector3d> cut;
        for (int c = 0; c < 3; ++c) {
          const Vector3d &a = q[c], &b = q[(c + 1) % 3];
          const double da = a[s.normal] - centre[s.normal], db = b[s.normal] - centre[s.normal];
          if ((da < 0) != (db < 0)) cut.push_back(a + (b - a) * (da / (da - db)));
        }
        if (cut.size() != 2) continue;
        const int steps = std::max(1, static_cast<int>((cut[1] - cut[0]).norm() / (0.5 * px_mm)));
        for (int k = 0; k <= steps; ++k) {
          int x, y;
          if (pixel(s, cut[0] + (cut[1] - cut[0]) * (double(k) / steps), &x, &y)) put(v, x, y, colour);
        }
      }
    }
    const uint8_t white[3] = {255, 255, 255};
    draw_text(rgb.data(), width, height, gap + v * (side + gap), header - 10, s.name, white);
  }
  const uint8_t white[3] = {255, 255, 255};
  draw_text(rgb.data(), width, height, gap, 3, title + " - RED PLACED, GREEN FITTED", white);
  png::write_png_rgb8(png_path, width, height, rgb.data());
}

}  // namespace pcisim::modeling
