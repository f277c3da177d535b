#include "modeling/picture/model_overview.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "modeling/picture/label_placement.h"
#include "modeling/picture/tiny_font.h"
#include "png/png_gray.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

// a view: image x and y as functions of the LPS point (mm)
struct View {
  const char* name;
  int ax_x, ax_y;         // LPS axes shown horizontally and vertically
  double sign_x, sign_y;  // +1: increasing to the right / downward
};

constexpr uint8_t kPalette[][3] = {{255, 80, 80},   {80, 200, 255},  {120, 255, 120}, {255, 200, 60},
                                   {220, 120, 255}, {255, 140, 0},   {0, 220, 200},   {255, 100, 180},
                                   {180, 255, 0},   {120, 160, 255}, {255, 255, 140}, {200, 200, 200}};

constexpr uint8_t kUnnamed[3] = {130, 140, 160}, kFalse[3] = {255, 30, 30}, kMissed[3] = {255, 230, 0};
constexpr uint8_t white[3] = {255, 255, 255};

// a label's importance: the trunks first, then the named side branches in the tree's order
int label_priority(const std::string& name) {
  for (const char* trunk : {"LM", "LAD", "LCx", "RCA", "LCA"}) {
    if (name == trunk) return 100;
  }
  return 50;
}

}  // namespace

bool is_named_branch(const std::string& name) {
  return name != "aorta" && !name.empty() && name.find('-') == std::string::npos;
}

void write_model_overview(const anatomy::Volume& ct, const anatomy::VesselTree& tree, const std::string& title,
                          const std::string& png_path, const OverviewMarks* marks) {
  // the CT's extent in LPS
  Vector3d lo = Vector3d::Constant(1e300), hi = -lo;
  for (int c = 0; c < 8; ++c) {
    const Vector3d ijk((c & 1) ? ct.dims[0] - 1 : 0, (c & 2) ? ct.dims[1] - 1 : 0, (c & 4) ? ct.dims[2] - 1 : 0);
    const Vector3d p = ct.index_to_physical_mm(ijk);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // front: x = L to the right... in radiological convention the patient's left is on the image's
  // right; LPS +x is the patient's left, so +x to the right; head (+z) up
  const View views[3] = {{"FRONT", 0, 2, +1, -1}, {"SIDE", 1, 2, +1, -1}, {"FEET", 0, 1, +1, +1}};
  const double extent = (hi - lo).maxCoeff();
  // no finer than the coarsest voxel, so every pixel of a view receives voxels
  const double px_mm = std::max(extent / 400.0, ct.spacing_mm.maxCoeff());
  std::array<int, 3> vw, vh;
  for (int v = 0; v < 3; ++v) {
    vw[v] = static_cast<int>((hi[views[v].ax_x] - lo[views[v].ax_x]) / px_mm) + 1;
    vh[v] = static_cast<int>((hi[views[v].ax_y] - lo[views[v].ax_y]) / px_mm) + 1;
  }
  const int header = 24, gap = 8, footer = 14;
  const int width = vw[0] + vw[1] + vw[2] + 4 * gap;
  const int height = header + std::max({vh[0], vh[1], vh[2]}) + gap + footer;
  std::vector<uint8_t> rgb(static_cast<size_t>(width) * height * 3, 0);
  std::array<int, 3> x0{gap, 2 * gap + vw[0], 3 * gap + vw[0] + vw[1]};

  // maximum intensity of every voxel splatted onto each view
  std::array<std::vector<float>, 3> mip;
  for (int v = 0; v < 3; ++v) mip[v].assign(static_cast<size_t>(vw[v]) * vh[v], -1024.0f);
  auto pixel = [&](int v, const Vector3d& p, int* x, int* y) {
    const View& w = views[v];
    const double fx = (p[w.ax_x] - lo[w.ax_x]) / px_mm, fy = (p[w.ax_y] - lo[w.ax_y]) / px_mm;
    *x = static_cast<int>(std::lround(w.sign_x > 0 ? fx : vw[v] - 1 - fx));
    *y = static_cast<int>(std::lround(w.sign_y > 0 ? fy : vh[v] - 1 - fy));
    return *x >= 0 && *y >= 0 && *x < vw[v] && *y < vh[v];
  };
  for (int64_t k = 0; k < ct.dims[2]; ++k) {
    for (int64_t j = 0; j < ct.dims[1]; ++j) {
      for (int64_t i = 0; i < ct.dims[0]; ++i) {
        const float h = ct.hu(i, j, k);
        if (h < -200) continue;
        const Vector3d p = ct.index_to_physical_mm(Vector3d(double(i), double(j), double(k)));
        for (int v = 0; v < 3; ++v) {
          int x, y;
          if (pixel(v, p, &x, &y)) {
            float& m = mip[v][static_cast<size_t>(y) * vw[v] + x];
            m = std::max(m, h);
          }
        }
      }
    }
  }
  // window -200..800 HU
  for (int v = 0; v < 3; ++v) {
    for (int y = 0; y < vh[v]; ++y) {
      for (int x = 0; x < vw[v]; ++x) {
        const float h = mip[v][static_cast<size_t>(y) * vw[v] + x];
        const uint8_t g = static_cast<uint8_t>(std::clamp((h + 200.0) / 1000.0 * 255.0, 0.0, 255.0));
        uint8_t* p = rgb.data() + (static_cast<size_t>(header + y) * width + x0[v] + x) * 3;
        p[0] = p[1] = p[2] = g;
      }
    }
  }
  // centerlines: the unnamed branches first (grey), the named ones over them in their colours
  auto put = [&](int v, int x, int y, const uint8_t* col) {
    uint8_t* p = rgb.data() + (static_cast<size_t>(header + y) * width + x0[v] + x) * 3;
    p[0] = col[0];
    p[1] = col[1];
    p[2] = col[2];
  };
  std::vector<const uint8_t*> colour(tree.branches.size(), kUnnamed);
  for (size_t b = 0, named = 0; b < tree.branches.size(); ++b) {
    if (is_named_branch(tree.branches[b].name))
      colour[b] = kPalette[named++ % (sizeof(kPalette) / sizeof(kPalette[0]))];
  }
  for (int pass = 0; pass < 2; ++pass) {
    for (size_t b = 0; b < tree.branches.size(); ++b) {
      const auto& br = tree.branches[b];
      if ((colour[b] == kUnnamed) != (pass == 0)) continue;
      for (int v = 0; v < 3; ++v) {
        for (size_t i = 0; i + 1 < br.points.size(); ++i) {
          const Vector3d a = br.points[i].position_m * 1e3, c = br.points[i + 1].position_m * 1e3;
          const int steps = std::max(1, static_cast<int>((c - a).norm() / (0.5 * px_mm)));
          for (int s = 0; s <= steps; ++s) {
            int x, y;
            if (pixel(v, a + (c - a) * (double(s) / steps), &x, &y)) put(v, x, y, colour[b]);
          }
        }
      }
    }
  }
  // against truth: false centerline as red crosses, missed truth as yellow dots
  if (marks) {
    for (int v = 0; v < 3; ++v) {
      for (const Vector3d& p : marks->missed_mm) {
        int x, y;
        if (pixel(v, p, &x, &y)) put(v, x, y, kMissed);
      }
      for (const Vector3d& p : marks->false_mm) {
        int x, y;
        if (!pixel(v, p, &x, &y)) continue;
        for (int d = -1; d <= 1; ++d) {
          if (x + d >= 0 && x + d < vw[v]) put(v, x + d, y, kFalse);
          if (y + d >= 0 && y + d < vh[v]) put(v, x, y + d, kFalse);
        }
      }
    }
  }
  // the named branches' labels near their far ends, placed so that none covers another; a label
  // moved off its end gets a leader line; each on a darkened box
  for (int v = 0; v < 3; ++v) {
    std::vector<Label> labels;
    std::vector<size_t> branch_of;
    for (size_t b = 0; b < tree.branches.size(); ++b) {
      const auto& br = tree.branches[b];
      int x, y;
      if (colour[b] == kUnnamed || br.points.empty() || !pixel(v, br.points.back().position_m * 1e3, &x, &y)) continue;
      labels.push_back({br.name, x, y, label_priority(br.name)});
      branch_of.push_back(b);
    }
    for (const PlacedLabel& pl : place_labels(labels, vw[v], vh[v])) {
      const Label& l = labels[pl.label];
      const uint8_t* col = colour[branch_of[pl.label]];
      if (pl.moved) {
        // from the anchor to the box's nearest point
        const int tx = std::clamp(l.anchor_x, pl.box.x, pl.box.x + pl.box.w - 1);
        const int ty = std::clamp(l.anchor_y, pl.box.y, pl.box.y + pl.box.h - 1);
        const int steps = std::max(std::abs(tx - l.anchor_x), std::abs(ty - l.anchor_y));
        for (int s = 0; s <= steps; ++s) {
          const int x = l.anchor_x + (tx - l.anchor_x) * s / std::max(1, steps);
          const int y = l.anchor_y + (ty - l.anchor_y) * s / std::max(1, steps);
          if (x >= 0 && y >= 0 && x < vw[v] && y < vh[v]) put(v, x, y, col);
        }
      }
      for (int y = pl.box.y; y < pl.box.y + pl.box.h; ++y) {
        for (int x = pl.box.x; x < pl.box.x + pl.box.w; ++x) {
          uint8_t* p = rgb.data() + (static_cast<size_t>(header + y) * width + x0[v] + x) * 3;
          for (int c = 0; c < 3; ++c) p[c] = static_cast<uint8_t>(p[c] / 4);
        }
      }
      draw_text(rgb.data(), width, height, x0[v] + pl.box.x + 1, header + pl.box.y + 1, l.text, col);
    }
  }
  {
    std::string legend = "LABELLED: NAMED BRANCHES; GREY: UNNAMED SIDE BRANCHES";
    draw_text(rgb.data(), width, height, gap, height - footer + 3, legend, white);
    if (marks) {
      const int x = gap + text_width(legend) + 18;
      draw_text(rgb.data(), width, height, x, height - footer + 3, "RED: FALSE CENTERLINE", kFalse);
      draw_text(rgb.data(), width, height, x + text_width("RED: FALSE CENTERLINE") + 18, height - footer + 3,
                "YELLOW: TRUTH MISSED", kMissed);
    }
  }
  for (int v = 0; v < 3; ++v) draw_text(rgb.data(), width, height, x0[v], header - 10, views[v].name, white);
  draw_text(rgb.data(), width, height, gap, 3, title, white);
  png::write_png_rgb8(png_path, width, height, rgb.data());
}

}  // namespace pcisim::modeling
