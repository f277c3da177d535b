// pcisim-us-kidney OUT_DIR [FRAMES ...]: B-mode images of the procedural kidney (anatomy/organ) through
// a tet mesh pressed by the probe, written as PNG (kidney_linear.png, kidney_curvilinear.png), and
// the time per frame (median, p95) over FRAMES frames (default 200) of a pressing motion. The
// deformation is analytic (no physics in this layer): a Kuhn tet grid over the kidney whose
// vertices are pushed along the beam, most under the probe. docs/ultrasound.md shows the PNG.
#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "anatomy/organ/kidney_phantom.h"
#include "realtime/percentile.h"
#include "ultrasound/tools/pressed_kidney.h"
#include "ultrasound/render/bmode_renderer.h"

namespace {

using pcisim::ultrasound::TetSnapshot;
using pcisim::ultrasound::tools::kidney_tets;
using pcisim::ultrasound::tools::press;

constexpr const char* kUsage =
    "usage: pcisim-us-kidney OUT_DIR [FRAMES [SAMPLES [CT_UM [THREADS [RENDERER]]]]]\n"
    "  B-mode images of the procedural kidney (linear and curvilinear probe) through a tet mesh pressed\n"
    "  by the probe: OUT_DIR/kidney_linear.png and kidney_curvilinear.png (created), and the time per\n"
    "  frame (median, p95, p99) over FRAMES frames of a pressing motion (default 200, 1..100000), 256\n"
    "  scanlines of SAMPLES samples each (default 256, 8..4096; issue #16's target is 256 x 512), the\n"
    "  kidney's CT at CT_UM micrometre voxels (default 1000, 100..4000; finer shows its boundaries\n"
    "  without the voxels' steps), each frame spread over THREADS threads (default 1, 1..8), drawn by\n"
    "  RENDERER: cpu (default) or cuda (the GPU: the time per frame then holds the copies to and from\n"
    "  it, and the kernels' own time is printed beside it; no PNG where the build has no libpng).\n"
    "  The deformation is analytic, not the physics (docs/ultrasound.md).\n";

// an integer argument in [lo, hi]; false (and why, on stderr) otherwise
bool read_count(const char* arg, const char* name, long lo, long hi, int* out) {
  char* end = nullptr;
  const long n = std::strtol(arg, &end, 10);
  if (end == arg || *end != '\0' || n < lo || n > hi) {
    std::fprintf(stderr, "pcisim-us-kidney: %s must be an integer in [%ld, %ld], got '%s'\n", name, lo, hi, arg);
    return false;
  }
  *out = static_cast<int>(n);
  return true;
}

int run(int argc, char** argv) {
  if (argc >= 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::printf("%s", kUsage);
    return 0;
  }
  if (argc < 2 || argc > 7 || argv[1][0] == '-') {
    std::fprintf(stderr, "%s", kUsage);
    return 2;
  }
  const std::string out = argv[1];
  int frames = 200, samples = 256, ct_um = 1000, threads = 1;
  if ((argc > 2 && !read_count(argv[2], "FRAMES", 1, 100000, &frames)) ||
      (argc > 3 && !read_count(argv[3], "SAMPLES", 8, 4096, &samples)) ||
      (argc > 4 && !read_count(argv[4], "CT_UM", 100, 4000, &ct_um)) ||
      (argc > 5 && !read_count(argv[5], "THREADS", 1, pcisim::ultrasound::kUsMaxThreads, &threads)))
    return 2;
  const std::string renderer_name = argc > 6 ? argv[6] : "cpu";
  if (renderer_name != "cpu" && renderer_name != "cuda") {
    std::fprintf(stderr, "pcisim-us-kidney: RENDERER must be cpu or cuda, got '%s'\n", renderer_name.c_str());
    return 2;
  }
  const auto renderer_kind =
      renderer_name == "cuda" ? pcisim::ultrasound::UsRenderer::kCuda : pcisim::ultrasound::UsRenderer::kCpu;
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) {
    std::fprintf(stderr, "pcisim-us-kidney: cannot create %s: %s\n", out.c_str(), ec.message().c_str());
    return 1;
  }
  pcisim::anatomy::KidneySpec spec;
  spec.ct_spacing_mm = ct_um * 1e-3;
  const auto kidney = pcisim::anatomy::make_kidney_phantom(spec);
  // each voxel's tissue gives its acoustic properties (ultrasound/echo/tissue_acoustics.h)
  const pcisim::anatomy::TissueMap tissue{kidney.tissue, pcisim::anatomy::kidney_tissue_names()};
  TetSnapshot mesh = kidney_tets(kidney.spec, 11.0);
  pcisim::ultrasound::ProbePose pose;
  pose.origin_mm = Eigen::Vector3d(0.0, kidney.ct.origin_mm.y(), 0.0);  // anterior face of the CT
  pose.beam = Eigen::Vector3d::UnitY();
  pose.lateral = Eigen::Vector3d::UnitZ();  // along the long axis
  const double push_max = 6.0;

  pcisim::ultrasound::UsSettings linear;
  linear.width_mm = 50.0;
  linear.height_px = samples;
  linear.threads = threads;
  linear.renderer = renderer_kind;
  pcisim::ultrasound::UsSettings curved;
  curved.geometry = pcisim::ultrasound::ProbeGeometry::kCurvilinear;
  curved.height_px = samples;
  curved.threads = threads;
  curved.renderer = renderer_kind;
  for (const auto& [name, settings] : {std::pair{"linear", linear}, std::pair{"curvilinear", curved}}) {
    pcisim::ultrasound::BModeRenderer renderer(kidney.ct, settings, &tissue);
    renderer.set_mesh(mesh);
    std::vector<double> ms, kernel_ms, pass_ms[5];
    ms.reserve(frames);
    kernel_ms.reserve(frames);
    for (int f = 0; f < frames; ++f) {
      press(mesh, push_max * 0.5 * (1.0 - std::cos(2.0 * 3.141592653589793 * f / 60.0)), kidney.spec.semi_axes_mm.y());
      const auto t0 = std::chrono::steady_clock::now();
      renderer.render(pose, 7, &mesh);
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      kernel_ms.push_back(renderer.last_gpu_kernel_ms());
      if (const float* pass = renderer.last_gpu_pass_ms())
        for (int k = 0; k < 5; ++k) pass_ms[k].push_back(pass[k]);
    }
    press(mesh, push_max / 2.0, kidney.spec.semi_axes_mm.y());
    const auto& image = renderer.render(pose, 7, &mesh);
    try {
      pcisim::ultrasound::write_png(out + "/kidney_" + name + ".png", image);
    } catch (const std::runtime_error& e) {
      // (a build without libpng, as on the GPU machine, times the frames all the same)
      if (std::string(e.what()).find("has no libpng") == std::string::npos) throw;
      std::printf("(no PNG: %s)\n", e.what());
    }
    const auto at = [&](double q) { return pcisim::realtime::percentile(ms, q); };
    const std::string where =
        renderer_kind == pcisim::ultrasound::UsRenderer::kCuda ? "cuda" : std::to_string(threads) + " thread(s)";
    std::printf("%s %dx%d, %s, %zu tets, %d frames: median %.2f ms, p95 %.2f ms, p99 %.2f ms\n", name,
                settings.width_px, settings.height_px, where.c_str(), mesh.tets.size(), frames, at(0.5), at(0.95),
                at(0.99));
    if (renderer_kind == pcisim::ultrasound::UsRenderer::kCuda) {
      const auto k = [&](double q) { return pcisim::realtime::percentile(kernel_ms, q); };
      std::printf("%s on the GPU's kernels alone (CUDA events): median %.3f ms, p95 %.3f ms, p99 %.3f ms\n", name,
                  k(0.5), k(0.95), k(0.99));
      const char* passes[5] = {"march", "echo", "axial PSF", "lateral PSF", "scan conversion"};
      std::printf("  median per pass:");
      for (int p = 0; p < 5; ++p)
        std::printf(" %s %.3f ms%s", passes[p], pcisim::realtime::percentile(pass_ms[p], 0.5), p < 4 ? "," : "\n");
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pcisim-us-kidney: %s\n", e.what());
    return 1;
  }
}
