#include "anatomy/case/case_overview.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "png/png_gray.h"
#include "realtime/percentile.h"

namespace pcisim::anatomy {
namespace {

// a view: image column along `right`, rows downward along -z; pixels of `mm_per_px`
struct Panel {
  int width = 0, height = 0;
  Eigen::Vector3d lo_mm;  // corner of the box the view covers
  int right = 0;          // axis shown left to right (0: x, 1: y)
  double mm_per_px = 1;
  std::vector<double> density;  // mean over the voxels that fell in the pixel
  std::vector<int> count;
  std::vector<uint8_t> overlay;  // drawn over the CT: vessels, the organ's outline, its beads

  bool pixel_of(const Eigen::Vector3d& p_mm, int* col, int* row) const {
    *col = static_cast<int>((p_mm[right] - lo_mm[right]) / mm_per_px);
    *row = height - 1 - static_cast<int>((p_mm.z() - lo_mm.z()) / mm_per_px);
    return *col >= 0 && *col < width && *row >= 0 && *row < height;
  }
};

// a disc of r_px pixels about p
void mark_disc(Panel& view, const Eigen::Vector3d& p_mm, int r_px) {
  int col = 0, row = 0;
  view.pixel_of(p_mm, &col, &row);
  for (int dr = -r_px; dr <= r_px; ++dr)
    for (int dc = -r_px; dc <= r_px; ++dc) {
      const int cc = col + dc, rr = row + dr;
      if (dr * dr + dc * dc > r_px * r_px || cc < 0 || cc >= view.width || rr < 0 || rr >= view.height) continue;
      view.overlay[static_cast<size_t>(rr) * view.width + cc] = 1;
    }
}

// the organ's outline (the edge of its projected triangles) and its beads as small discs
void draw_organ(const Organ& organ, Panel& view) {
  std::vector<uint8_t> covered(view.overlay.size(), 0);
  auto to_px = [&view](const Eigen::Vector3d& p_m) {
    const Eigen::Vector3d p = p_m * 1e3;
    return Eigen::Vector2d((p[view.right] - view.lo_mm[view.right]) / view.mm_per_px,
                           view.height - (p.z() - view.lo_mm.z()) / view.mm_per_px);
  };
  for (const auto& t : organ.surface.triangles) {
    const Eigen::Vector2d a = to_px(organ.surface.vertices_m[t[0]]), b = to_px(organ.surface.vertices_m[t[1]]),
                          d = to_px(organ.surface.vertices_m[t[2]]);
    const double area = (b - a).x() * (d - a).y() - (d - a).x() * (b - a).y();
    if (area == 0.0) continue;
    const int c0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), d.x()}))));
    const int c1 = std::min(view.width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), d.x()}))));
    const int r0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), d.y()}))));
    const int r1 = std::min(view.height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), d.y()}))));
    for (int r = r0; r <= r1; ++r)
      for (int col = c0; col <= c1; ++col) {
        // the pixel's centre inside the projected triangle (either winding)
        const Eigen::Vector2d q(col + 0.5, r + 0.5);
        const double wb = ((q - a).x() * (d - a).y() - (d - a).x() * (q - a).y()) / area;
        const double wd = ((b - a).x() * (q - a).y() - (q - a).x() * (b - a).y()) / area;
        if (wb >= 0 && wd >= 0 && wb + wd <= 1) covered[static_cast<size_t>(r) * view.width + col] = 1;
      }
  }
  // covered pixels with an uncovered neighbour: a one-pixel outline that leaves the CT visible
  for (int r = 0; r < view.height; ++r)
    for (int col = 0; col < view.width; ++col) {
      if (!covered[static_cast<size_t>(r) * view.width + col]) continue;
      bool edge = r == 0 || col == 0 || r == view.height - 1 || col == view.width - 1;
      for (int k = 0; !edge && k < 4; ++k) {
        const int rr = r + (k == 0) - (k == 1), cc = col + (k == 2) - (k == 3);
        edge = !covered[static_cast<size_t>(rr) * view.width + cc];
      }
      if (edge) view.overlay[static_cast<size_t>(r) * view.width + col] = 1;
    }
  for (const auto& f : organ.fiducials_m) mark_disc(view, f * 1e3, 1);
}

}  // namespace

void write_case_overview(const Case& c, const std::string& png_path) {
  // the box: the CT's extent, else the vessels' with a margin
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  if (c.ct) {
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d ijk((k & 1) ? c.ct->dims[0] - 1 : 0, (k & 2) ? c.ct->dims[1] - 1 : 0,
                                (k & 4) ? c.ct->dims[2] - 1 : 0);
      const Eigen::Vector3d p = c.ct->index_to_physical_mm(ijk);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  } else {
    for (const auto& b : c.vessels.branches)
      for (const auto& p : b.points) {
        lo = lo.cwiseMin(p.position_m * 1e3);
        hi = hi.cwiseMax(p.position_m * 1e3);
      }
    if (c.organ)
      for (const auto& v : c.organ->surface.vertices_m) {
        lo = lo.cwiseMin(v * 1e3);
        hi = hi.cwiseMax(v * 1e3);
      }
    lo -= Eigen::Vector3d::Constant(20);
    hi += Eigen::Vector3d::Constant(20);
  }
  if (!(lo.array() < hi.array()).all()) throw std::runtime_error(png_path + ": the case has no extent to draw");
  // at most 480 px a view, and never finer than the CT's voxels (finer bins would alias)
  double mm_per_px = std::max({hi.x() - lo.x(), hi.y() - lo.y(), hi.z() - lo.z()}) / 480.0;
  if (c.ct) mm_per_px = std::max(mm_per_px, c.ct->spacing_mm.maxCoeff());
  Panel views[2];
  for (int v = 0; v < 2; ++v) {
    Panel& p = views[v];
    p.right = v;
    p.lo_mm = lo;
    p.mm_per_px = mm_per_px;
    p.width = std::max(1, static_cast<int>((hi[v] - lo[v]) / mm_per_px) + 1);
    p.height = std::max(1, static_cast<int>((hi.z() - lo.z()) / mm_per_px) + 1);
    p.density.assign(static_cast<size_t>(p.width) * p.height, 0.0);
    p.count.assign(p.density.size(), 0);
    p.overlay.assign(p.density.size(), 0);
  }
  // the CT: mean density above air along each pixel's line of sight (nearest voxel, one sample
  // per voxel spacing), so no pixel is left without voxels
  if (c.ct) {
    const Volume& ct = *c.ct;
    const double step = ct.spacing_mm.minCoeff();
    for (auto& view : views) {
      const int depth_axis = 1 - view.right;
      for (int row = 0; row < view.height; ++row)
        for (int col = 0; col < view.width; ++col) {
          Eigen::Vector3d p = lo;
          p[view.right] = lo[view.right] + (col + 0.5) * mm_per_px;
          p.z() = lo.z() + (view.height - 1 - row + 0.5) * mm_per_px;
          const size_t n = static_cast<size_t>(row) * view.width + col;
          for (p[depth_axis] = lo[depth_axis]; p[depth_axis] <= hi[depth_axis]; p[depth_axis] += step) {
            const Eigen::Vector3d ijk = ct.physical_to_index(p);
            const int64_t i = std::llround(ijk.x()), j = std::llround(ijk.y()), k = std::llround(ijk.z());
            if (i < 0 || j < 0 || k < 0 || i >= ct.dims[0] || j >= ct.dims[1] || k >= ct.dims[2]) continue;
            view.density[n] += std::max(0.0, static_cast<double>(ct.hu(i, j, k)) + 1000.0);
            ++view.count[n];
          }
        }
    }
  }
  // the vessels: discs of each point's radius
  for (auto& view : views)
    for (const auto& b : c.vessels.branches)
      for (const auto& pt : b.points) {
        const Eigen::Vector3d p = pt.position_m * 1e3;
        mark_disc(view, p, std::max(1, static_cast<int>(std::lround(pt.radius_m * 1e3 / mm_per_px))));
      }
  if (c.organ)
    for (auto& view : views) draw_organ(*c.organ, view);
  // mean density per pixel (bins of voxels do not all hold the same number)
  for (auto& view : views)
    for (size_t n = 0; n < view.density.size(); ++n)
      if (view.count[n] > 0) view.density[n] /= view.count[n];
  // side by side, 8 px apart; grey from 0 to the 99th percentile of each view's density
  const int gap = 8, width = views[0].width + gap + views[1].width;
  const int height = std::max(views[0].height, views[1].height);
  std::vector<uint8_t> image(static_cast<size_t>(width) * height, 0);
  int x0 = 0;
  for (const auto& view : views) {
    const double p99 = realtime::percentile(view.density, 0.99);
    const double top = p99 > 0 ? p99 : 1.0;
    for (int r = 0; r < view.height; ++r)
      for (int col = 0; col < view.width; ++col) {
        const size_t n = static_cast<size_t>(r) * view.width + col;
        const double g = view.overlay[n] ? 255.0 : 200.0 * std::min(1.0, view.density[n] / top);
        image[static_cast<size_t>(r) * width + x0 + col] = static_cast<uint8_t>(g);
      }
    x0 += view.width + gap;
  }
  // enlarged by whole pixels to about 480 rows, for the eye
  const int zoom = std::max(1, 480 / std::max(height, 1));
  std::vector<uint8_t> big(static_cast<size_t>(width) * zoom * height * zoom);
  for (int r = 0; r < height * zoom; ++r)
    for (int col = 0; col < width * zoom; ++col)
      big[static_cast<size_t>(r) * width * zoom + col] = image[static_cast<size_t>(r / zoom) * width + col / zoom];
  png::write_png_gray8(png_path, width * zoom, height * zoom, big.data());
}

}  // namespace pcisim::anatomy
