// pcisim-us-frames: the kidney scene's B-mode as a person would look at it (issue #32 item 4).
// The scene (scenes/kidney.json by default) is built as the server builds it: its case (the
// procedural kidney with its tissue map), its soft-tissue physics and probe. The probe images the
// organ at rest, then is driven along its beam by the physics until it touches the organ and
// PRESS_MM further, and held; each probe (3.5 MHz curvilinear, 7.5 MHz linear) writes one PNG:
// the frame at rest beside the pressed one, the tissues labelled where the case's tissue map
// says they are (through the deformed tets to the rest CT): capsule, cortex, pyramid, sinus,
// calyx (urine) and the shadow behind a bead.
#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "modeling/picture/tiny_font.h"
#include "physics/soft_tissue/tissue_scene.h"
#include "png/png_gray.h"
#include "server/case_builder.h"
#include "server/scene/scene.h"
#include "ultrasound/mapping/tet_locator.h"
#include "ultrasound/render/bmode_renderer.h"

namespace {

namespace us = pcisim::ultrasound;
namespace st = pcisim::physics::soft_tissue;
using Eigen::Vector3d;

// the physics' probe pose as the renderer's (as server/ultrasound_loop.cc takes it)
us::ProbePose image_pose(const st::ProbePose& p) {
  const Eigen::Matrix3d r = p.rotation.toRotationMatrix();
  us::ProbePose out;
  out.origin_mm = p.position_m * 1e3;
  out.lateral = r.col(0);
  out.beam = r.col(2);
  return out;
}

us::TetSnapshot snapshot(const st::TissueScene& scene) {
  us::TetSnapshot s;
  s.rest_mm = scene.model().tet_vertices_m * 1e3;
  s.current_mm = scene.tet_vertices_m() * 1e3;
  s.tets = scene.model().tets;
  return s;
}

// one frame with what each display pixel shows: the tissue label at its rest place (-1 outside
// the fan)
struct Frame {
  us::BModeImage image;
  std::vector<int> label;
};

int label_at(const pcisim::anatomy::TissueMap& map, const Vector3d& rest_mm) {
  const pcisim::anatomy::Volume& v = map.labels;
  const Vector3d u = v.physical_to_index(rest_mm);
  int64_t i[3];
  for (int k = 0; k < 3; ++k) i[k] = std::clamp<int64_t>(std::llround(u[k]), 0, v.dims[k] - 1);
  return v.hu_i16[v.linear_index(i[0], i[1], i[2])];
}

Frame render(us::BModeRenderer& renderer, const us::ProbePose& pose, uint64_t seed, const us::TetSnapshot& mesh,
             const pcisim::anatomy::TissueMap& map) {
  Frame f;
  f.image = renderer.render(pose, seed, &mesh);
  const us::UsSettings& s = renderer.settings();
  us::TetLocator locator;
  locator.build(mesh);
  f.label.assign(f.image.pixels.size(), -1);
  for (int r = 0; r < s.height_px; ++r)
    for (int c = 0; c < s.width_px; ++c) {
      double bc = 0, br = 0;
      if (!us::display_to_beam(s, c, r, &bc, &br)) continue;
      const Vector3d x = us::display_pixel_to_world(s, pose, c, r);
      Vector3d q = x;
      if (!locator.to_rest(x, &q)) q = x;
      f.label[static_cast<size_t>(r) * s.width_px + c] = label_at(map, q);
    }
  return f;
}

int find_label(const pcisim::anatomy::TissueMap& map, const std::string& name) {
  for (size_t i = 0; i < map.names.size(); ++i)
    if (map.names[i] == name) return static_cast<int>(i);
  return -2;
}

struct Mark {
  int x = -1, y = -1;
  std::string text;
};

// the pixel of `label` nearest (cx, cy) whose neighbours `margin` pixels away hold it too
Mark nearest(const Frame& f, int w, int h, int label, int cx, int cy, int margin, const std::string& text) {
  Mark best;
  best.text = text;
  double best_d = 1e30;
  auto is = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < w && y < h && f.label[static_cast<size_t>(y) * w + x] == label;
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!is(x, y) || !is(x - margin, y) || !is(x + margin, y) || !is(x, y - margin) || !is(x, y + margin)) continue;
      const double d = std::hypot(x - cx, y - cy);
      if (d < best_d) best_d = d, best = {x, y, text};
    }
  return best;
}

// the anatomy a sonographer names: the capsule (the first cortex down the central column),
// cortex, a pyramid, the sinus, a calyx and the shadow under the bead nearest the centre
std::vector<Mark> marks(const Frame& f, const pcisim::anatomy::TissueMap& map, const us::UsSettings& s) {
  const int w = s.width_px, h = s.height_px;
  const int cortex = find_label(map, "renal cortex"), medulla = find_label(map, "renal medulla"),
            sinus = find_label(map, "renal sinus fat"), urine = find_label(map, "urine"),
            steel = find_label(map, "steel");
  std::vector<Mark> out;
  // 1.5 mm inside its tissue (display rows span the depth, or a little more in a fan)
  const int m = std::max(2, static_cast<int>(std::lround(1.5 / (s.depth_mm / h))));
  for (int y = 0; y < h; ++y)
    if (f.label[static_cast<size_t>(y) * w + w / 2] == cortex) {
      out.push_back({w / 2, y, "CAPSULE"});
      break;
    }
  out.push_back(nearest(f, w, h, cortex, w / 4, h / 4, m, "CORTEX"));
  out.push_back(nearest(f, w, h, medulla, w / 2, h / 3, m, "PYRAMID"));
  out.push_back(nearest(f, w, h, sinus, w / 2, h / 2, m, "SINUS FAT"));
  out.push_back(nearest(f, w, h, urine, 3 * w / 4, h / 2, m / 3, "CALYX"));
  const Mark bead = nearest(f, w, h, steel, w / 2, h / 2, 0, "");
  if (bead.x >= 0) out.push_back({bead.x, std::min(h - 1, bead.y + h / 12), "SHADOW"});
  std::erase_if(out, [](const Mark& k) { return k.x < 0; });
  return out;
}

void put(std::vector<uint8_t>& rgb, int w, int h, int x, int y, const uint8_t c[3]) {
  if (x < 0 || y < 0 || x >= w || y >= h) return;
  std::copy(c, c + 3, &rgb[3 * (static_cast<size_t>(y) * w + x)]);
}

// text with a dark outline, so it reads over bright speckle
void outlined(std::vector<uint8_t>& rgb, int w, int h, int x, int y, const std::string& t, const uint8_t c[3],
              int scale) {
  const uint8_t dark[3] = {0, 0, 0};
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (dx || dy) pcisim::modeling::draw_text(rgb.data(), w, h, x + dx, y + dy, t, dark, scale);
  pcisim::modeling::draw_text(rgb.data(), w, h, x, y, t, c, scale);
}

// the two frames side by side under their titles, each mark a ring with its name beside it
void write_pair(const std::string& path, const Frame& a, const Frame& b, const std::vector<Mark>& ma,
                const std::vector<Mark>& mb, const std::string& ta, const std::string& tb, int scale) {
  const int w = a.image.width, h = a.image.height, gap = 8, top = 12 * scale;
  const int W = 2 * w + gap, H = h + top;
  std::vector<uint8_t> rgb(static_cast<size_t>(W) * H * 3, 0);
  const uint8_t yellow[3] = {255, 220, 40}, white[3] = {255, 255, 255};
  int x0 = 0;
  for (const auto* side : {&a, &b}) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const uint8_t g = side->image.pixels[static_cast<size_t>(y) * w + x];
        const uint8_t c[3] = {g, g, g};
        put(rgb, W, H, x0 + x, top + y, c);
      }
    x0 += w + gap;
  }
  outlined(rgb, W, H, 2, 2 * scale, ta, white, scale);
  outlined(rgb, W, H, w + gap + 2, 2 * scale, tb, white, scale);
  x0 = 0;
  for (const auto* marks : {&ma, &mb}) {
    std::vector<std::array<int, 4>> placed;  // x, y, width, height of each text
    for (const Mark& k : *marks) {
      const int cx = x0 + k.x, cy = top + k.y, r = 2 * scale;
      for (int t = 0; t < 32; ++t) {
        const double a = 2.0 * 3.141592653589793 * t / 32;
        put(rgb, W, H, cx + static_cast<int>(std::lround(r * std::cos(a))),
            cy + static_cast<int>(std::lround(r * std::sin(a))), yellow);
      }
      const int tw = pcisim::modeling::text_width(k.text, scale), th = 8 * scale;
      int tx = k.x + r + 3 + tw < w ? cx + r + 3 : cx - r - 3 - tw, ty = cy - th / 2;
      // stepped down until it overlaps no earlier label
      for (int tries = 0; tries < 20; ++tries) {
        bool clear = true;
        for (const auto& p : placed)
          clear = clear && (tx + tw < p[0] || p[0] + p[2] < tx || ty + th < p[1] || p[1] + p[3] < ty);
        if (clear) break;
        ty += th + 2;
      }
      placed.push_back({tx, ty, tw, th});
      // a leader from the ring to the text when the text had to move off it
      const int lx = tx > cx ? tx - 1 : tx + tw + 1, ly = ty + th / 2;
      const int steps = std::max(std::abs(lx - cx), std::abs(ly - cy));
      for (int t = r + 1; t <= steps; ++t)
        put(rgb, W, H, cx + (lx - cx) * t / std::max(steps, 1), cy + (ly - cy) * t / std::max(steps, 1), yellow);
      outlined(rgb, W, H, tx, ty, k.text, yellow, scale);
    }
    x0 += w + gap;
  }
  pcisim::png::write_png_rgb8(path, W, H, rgb.data());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "pcisim-us-frames: the kidney scene's B-mode at rest and pressed, at 3.5 MHz (curvilinear) and 7.5 MHz "
      "(linear), the tissues labelled (docs/ultrasound.md)"};
  std::string scene_file = "scenes/kidney.json", out = "docs/ultrasound";
  double press_mm = 10.0;
  int width = 400, height = 512;
  double ct_mm = 0.5;
  app.add_option("--scene", scene_file, "a soft-tissue scene with probe contact")->check(CLI::ExistingFile);
  app.add_option("--out", out, "folder for the PNGs (created)");
  app.add_option("--press-mm", press_mm, "how far the probe presses past first touching the organ")
      ->check(CLI::Range(0.0, 20.0));
  app.add_option("--ct-mm", ct_mm, "the procedural kidney's CT voxel (the scene's is 1 mm)")
      ->check(CLI::Range(0.2, 4.0));
  app.add_option("--width", width, "scanlines (display columns)")->check(CLI::Range(64, 1024));
  app.add_option("--height", height, "samples per scanline (display rows)")->check(CLI::Range(64, 2048));
  CLI11_PARSE(app, argc, argv);
  try {
    const pcisim::server::Scene scene = pcisim::server::load_scene_file(scene_file);
    if (!scene.world.soft_tissue || !scene.world.probe_contact || !scene.ultrasound)
      throw std::invalid_argument(scene_file + ": needs the soft_tissue, probe_contact and ultrasound effects");
    // the procedural kidney at the finer CT; a case folder as it is
    const auto anatomy = scene.organ == "kidney"
                             ? std::make_shared<const pcisim::anatomy::Case>(pcisim::server::kidney_case(scene, ct_mm))
                             : pcisim::server::build_case(scene);
    if (!anatomy->organ || !anatomy->organ->tissue || !anatomy->ct)
      throw std::invalid_argument(scene_file + ": its case has no organ with a tissue map and a CT");
    const pcisim::anatomy::TissueMap& map = *anatomy->organ->tissue;
    std::filesystem::create_directories(out);
    const double step_s = 1.0 / scene.physics_rate_hz;

    struct Probe {
      const char* file;
      const char* title;
      us::UsSettings settings;
    };
    us::UsSettings curved = scene.ultrasound->settings, linear = scene.ultrasound->settings;
    curved.geometry = us::ProbeGeometry::kCurvilinear;
    curved.frequency_mhz = 3.5;
    curved.depth_mm = 80.0;
    linear.geometry = us::ProbeGeometry::kLinear;
    linear.frequency_mhz = 7.5;
    linear.width_mm = 40.0;
    linear.depth_mm = 50.0;
    // the time-gain compensation a sonographer would set for the kidney at each frequency: the
    // round trip's loss in tissue between fat (0.6 dB/cm/MHz) and kidney (0.9), 2 x 0.8 f dB/cm
    for (us::UsSettings* s : {&curved, &linear}) {
      s->width_px = width;
      s->height_px = height;
      s->tgc_db_per_cm = 2.0 * 0.8 * s->frequency_mhz;
    }
    const Probe probes[] = {{"kidney_curvilinear_3.5mhz.png", "3.5 MHZ CURVED", curved},
                            {"kidney_linear_7.5mhz.png", "7.5 MHZ LINEAR", linear}};

    // the physics at rest, the probe where the scene starts it
    st::TissueScene physics(*anatomy->organ, *scene.world.soft_tissue, scene.world.probe_contact, step_s);
    st::ProbePose pose = physics.probe_pose();
    physics.step(&pose);
    const us::TetSnapshot rest = snapshot(physics);
    const us::ProbePose rest_pose = image_pose(pose);
    // down the beam at 10 mm/s until it pushes on the organ, then press_mm further at 5 mm/s and
    // hold a second
    const Vector3d beam = pose.rotation.toRotationMatrix().col(2);
    double travelled_mm = 0.0, touched_mm = -1.0;
    for (int i = 0; i < 2000 && (touched_mm < 0.0 || travelled_mm < touched_mm + press_mm); ++i) {
      const double v_mm_s = touched_mm < 0.0 ? 10.0 : 5.0;
      const double dx = std::min(v_mm_s * step_s, touched_mm < 0.0 ? 1e9 : touched_mm + press_mm - travelled_mm);
      travelled_mm += dx;
      pose.position_m += beam * dx * 1e-3;
      physics.step(&pose);
      if (touched_mm < 0.0 && physics.probe_force_n().norm() > 0.05) touched_mm = travelled_mm;
    }
    if (touched_mm < 0.0) throw std::runtime_error("the probe never touched the organ");
    if (travelled_mm < touched_mm + press_mm - 1e-6)
      throw std::runtime_error("the probe pressed " + std::to_string(travelled_mm - touched_mm) + " mm, not " +
                               std::to_string(press_mm) + " (too many physics steps: a faster scene?)");
    for (int i = 0; i < static_cast<int>(1.0 / step_s); ++i) physics.step(&pose);
    const us::TetSnapshot pressed = snapshot(physics);
    std::printf("the probe touched the organ after %.1f mm and pressed %.1f mm more (force %.2f N)\n", touched_mm,
                travelled_mm - touched_mm, physics.probe_force_n().norm());

    for (const Probe& p : probes) {
      us::BModeRenderer renderer(*anatomy->ct, p.settings, &map);
      const uint64_t seed = scene.ultrasound->speckle_seed;
      const Frame a = render(renderer, rest_pose, seed, rest, map);
      const Frame b = render(renderer, image_pose(pose), seed, pressed, map);
      const int scale = width >= 384 ? 2 : 1;
      const std::string path = out + "/" + p.file;
      write_pair(path, a, b, marks(a, map, p.settings), marks(b, map, p.settings), std::string(p.title) + " REST",
                 std::string(p.title) + " PRESSED " + std::to_string(static_cast<int>(std::lround(press_mm))) + " MM",
                 scale);
      std::printf("wrote %s\n", path.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pcisim-us-frames: %s\n", e.what());
    return 1;
  }
}
