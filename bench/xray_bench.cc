// pcisim-bench xray: what DRR accuracy costs. The seeded thorax phantom (512 x 512 x 256 at 0.7 mm)
// seen by a C-arm at LAO 30 / CRA 20 on 512^2 and 1024^2 detectors (same field of view): the exact
// Siddon projector is the reference and is timed too; the trilinear marcher on the CPU (and on the
// GPU when built with CUDA and one is present) is timed and compared with it for steps of 2, 1,
// 0.5 and 0.25 voxel. Writes xray.md, xray.json and (with python3-matplotlib) xray.png into
// docs/benchmarks/ or --out DIR.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_registry.h"
#include "bench/machine_info.h"
#include "xray/geometry/c_arm.h"
#include "xray/phantom/thorax_phantom.h"
#include "xray/projectors/attenuation_volume.h"
#include "xray/projectors/siddon_projector.h"
#include "xray/projectors/trilinear_projector.h"
#ifdef PCISIM_HAVE_CUDA
#include "xray/projectors/cuda_projector.h"
#endif

namespace pcisim::bench {
namespace {

using namespace pcisim::xray;

struct Options {
  bool quick = false;
  std::string out_dir = "docs/benchmarks";
  int threads = 0;
};

struct Row {
  std::string projector;  // exact, cpu, cuda
  int detector = 0;
  double step = 0;        // 0 for exact
  double median_ms = 0, p99_ms = 0;
  double cpu_ms = 0;  // process CPU time per frame (all threads); wall ~ cpu / threads when no one else runs
  int frames = 0;
  double rmse_rel = 0, max_rel = 0;  // vs exact, relative to the largest exact line integral
};

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const size_t i = static_cast<size_t>(pos);
  const double f = pos - i;
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v.back();
}

double process_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

// wall ms of each frame; *cpu_ms: mean process CPU ms per frame
template <class Fn>
std::vector<double> time_frames(int warmup, int frames, double* cpu_ms, Fn&& fn) {
  for (int i = 0; i < warmup; ++i) fn();
  std::vector<double> ms;
  const double c0 = process_cpu_ms();
  for (int i = 0; i < frames; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  *cpu_ms = (process_cpu_ms() - c0) / frames;
  return ms;
}

void errors(const Image& got, const Image& ref, Row* row) {
  double peak = 0, sq = 0, worst = 0;
  for (float v : ref.pixels) peak = std::max(peak, double(v));
  for (size_t n = 0; n < ref.pixels.size(); ++n) {
    const double e = double(got.pixels[n]) - ref.pixels[n];
    sq += e * e;
    worst = std::max(worst, std::abs(e));
  }
  row->rmse_rel = std::sqrt(sq / ref.pixels.size()) / peak;
  row->max_rel = worst / peak;
}

int run(const std::vector<std::string>& args) {
  Options o;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--quick") {
      o.quick = true;
    } else if (args[i] == "--out" && i + 1 < args.size()) {
      o.out_dir = args[++i];
    } else if (args[i] == "--threads" && i + 1 < args.size()) {
      o.threads = std::atoi(args[++i].c_str());
    } else {
      std::printf(
          "pcisim-bench xray [--quick] [--out DIR (docs/benchmarks)] [--threads N (all cores)]\n"
          "  full: 512^2 and 1024^2 detectors, steps 2, 1, 0.5, 0.25 voxel on CPU and GPU\n"
          "  --quick: CPU on 512^2 only with steps 1 and 0.5, fewer frames; the GPU sweep stays full\n");
      return args[i] == "--help" ? 0 : 2;
    }
  }
  std::filesystem::create_directories(o.out_dir);
  const std::string machine = machine_info();
  std::printf("xray: %s\n", machine.c_str());

  const auto t0 = std::chrono::steady_clock::now();
  ThoraxPhantomSpec spec;  // 512 x 512 x 256 at 0.7 mm, seed 1, iodine lumens
  const Volume volume = make_thorax_phantom(spec);
  const double phantom_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const auto t1 = std::chrono::steady_clock::now();
  const AttenuationVolume att(volume);
  const double mu_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
  std::printf("xray: phantom %.0f ms, attenuation volume %.0f ms\n", phantom_ms, mu_ms);

  const CArmPose pose{30, 20, Eigen::Vector3d::Zero()};  // LAO 30 CRA 20, isocentre at the heart
  const std::vector<int> detectors = o.quick ? std::vector<int>{512} : std::vector<int>{512, 1024};
  const std::vector<double> cpu_steps = o.quick ? std::vector<double>{1, 0.5} : std::vector<double>{2, 1, 0.5, 0.25};
  const std::vector<double> gpu_steps = {2, 1, 0.5, 0.25};
  const int cpu_frames = o.quick ? 3 : 5;
  std::vector<Row> rows;
  std::string gpu_name;
  int cpu_threads = 0;

  SiddonProjector exact(att, o.threads);
  TrilinearProjector cpu(att, {.threads = o.threads});
#ifdef PCISIM_HAVE_CUDA
  std::unique_ptr<CudaTrilinearProjector> gpu;
  std::string why;
  if (CudaTrilinearProjector::available(&why)) {
    gpu = std::make_unique<CudaTrilinearProjector>(att);
    gpu_name = gpu->device_name();
  } else {
    std::printf("xray: GPU sweep skipped: %s\n", why.c_str());
  }
#endif
  cpu_threads = o.threads > 0 ? o.threads : static_cast<int>(std::thread::hardware_concurrency());

  for (const int n : detectors) {
    CArmSpec c;
    c.width = c.height = n;
    c.pixel_mm = 0.4 * 512.0 / n;  // the same 205 mm field on the detector
    const DetectorGeometry g = c_arm_geometry(c, pose);
    Image ref, img;
    ref.resize(n, n);
    img.resize(n, n);
    {
      Row r{"exact", n, 0};
      const auto ms = time_frames(1, cpu_frames, &r.cpu_ms, [&] { exact.project(g, &ref); });
      r.median_ms = percentile(ms, 0.5);
      r.p99_ms = percentile(ms, 0.99);
      r.frames = cpu_frames;
      rows.push_back(r);
      std::printf("xray: %4d^2 exact          %9.1f ms (p99 %.1f, cpu %.1f)\n", n, r.median_ms, r.p99_ms, r.cpu_ms);
    }
    const bool cpu_here = !o.quick || n == 512;
    for (const double step : cpu_steps) {
      if (!cpu_here) break;
      cpu.set_options({.step_voxels = step, .skip_empty = true});
      Row r{"cpu", n, step};
      const auto ms = time_frames(1, cpu_frames, &r.cpu_ms, [&] { cpu.project(g, &img); });
      r.median_ms = percentile(ms, 0.5);
      r.p99_ms = percentile(ms, 0.99);
      r.frames = cpu_frames;
      errors(img, ref, &r);
      rows.push_back(r);
      std::printf("xray: %4d^2 cpu  step %.2f %9.1f ms (p99 %.1f, cpu %.1f)  rmse %.4f %%  max %.4f %%\n", n, step,
                  r.median_ms, r.p99_ms, r.cpu_ms, 100 * r.rmse_rel, 100 * r.max_rel);
    }
#ifdef PCISIM_HAVE_CUDA
    if (gpu) {
      for (const double step : gpu_steps) {
        gpu->set_options({.step_voxels = step, .skip_empty = true});
        gpu->project(g, &img);  // the image for the error; also a warm-up
        Row r{"cuda", n, step};
        const int runs = o.quick ? 100 : 200;
        const auto ms_f = gpu->time_kernel_ms(g, 10, runs);
        const std::vector<double> ms(ms_f.begin(), ms_f.end());
        r.median_ms = percentile(ms, 0.5);
        r.p99_ms = percentile(ms, 0.99);
        r.frames = runs;
        errors(img, ref, &r);
        rows.push_back(r);
        std::printf("xray: %4d^2 cuda step %.2f %9.3f ms (p99 %.3f)  rmse %.4f %%  max %.4f %%\n", n, step, r.median_ms,
                    r.p99_ms, 100 * r.rmse_rel, 100 * r.max_rel);
      }
    }
#endif
  }

  // json
  {
    std::ofstream f(o.out_dir + "/xray.json");
    f << "{\n" << fmt::format("  \"machine\": \"{}\",\n  \"gpu\": \"{}\",\n  \"cpu_threads\": {},\n", machine,
                              gpu_name, cpu_threads);
    f << fmt::format("  \"quick\": {},\n  \"phantom\": {{\"dims\": [512, 512, 256], \"spacing_mm\": 0.7, \"seed\": 1, "
                     "\"build_ms\": {:.1f}, \"attenuation_ms\": {:.1f}}},\n",
                     o.quick, phantom_ms, mu_ms);
    f << "  \"c_arm\": {\"primary_deg\": 30, \"secondary_deg\": 20, \"sid_mm\": 1100, \"sad_mm\": 750, "
         "\"field_mm\": 204.8},\n  \"rows\": [\n";
    for (size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      f << fmt::format("    {{\"projector\": \"{}\", \"detector\": {}, \"step_voxels\": {}, \"median_ms\": {:.4f}, "
                       "\"p99_ms\": {:.4f}, \"cpu_ms\": {:.2f}, \"frames\": {}, \"rmse_rel\": {:.6g}, \"max_rel\": {:.6g}}}{}\n",
                       r.projector, r.detector, r.step, r.median_ms, r.p99_ms, r.cpu_ms, r.frames, r.rmse_rel, r.max_rel,
                       i + 1 < rows.size() ? "," : "");
    }
    f << "  ]\n}\n";
  }
  // markdown
  {
    std::ofstream f(o.out_dir + "/xray.md");
    f << "# X-ray projection (DRR) benchmark\n\n";
    f << fmt::format("Generated by `pcisim-bench xray{}` on {}; {} CPU threads{}.\n\n", o.quick ? " --quick" : "", machine,
                     cpu_threads, gpu_name.empty() ? "; no GPU" : "; GPU: " + gpu_name);
    f << "Phantom: seeded thorax (seed 1), 512 x 512 x 256 voxels at 0.7 mm, iodine lumens at 400 HU "
      << fmt::format("(built in {:.0f} ms; HU to mu in {:.0f} ms). ", phantom_ms, mu_ms)
      << "C-arm LAO 30 / CRA 20, SID 1100 mm, SAD 750 mm, isocentre at the heart centre; 512^2 detector at 0.4 mm, "
         "1024^2 at 0.2 mm (same field). mu_water 0.02 /mm, HU < -800 is air.\n\n";
    f << "Errors are against the exact (Siddon) projection of the same geometry: RMSE and worst pixel, relative to the "
         "largest exact line integral. CPU times: wall clock per frame, median and p99 of "
      << cpu_frames << " frames after one warm-up (p99 of so few frames is their maximum), and the process CPU time "
         "per frame (wall x threads when nothing else runs; more wall than that means the cores were shared). "
         "GPU times: kernel only, "
         "CUDA events, median and p99 of 100-200 launches after 10 warm-up launches.\n\n";
    f << "| projector | detector | step (voxel) | median ms | p99 ms | CPU ms (all threads) | RMSE % of max | max % of max |\n";
    f << "|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows) {
      f << fmt::format("| {} | {}^2 | {} | {:.3f} | {:.3f} | {} | {} | {} |\n", r.projector, r.detector,
                       r.projector == "exact" ? std::string("-") : fmt::format("{}", r.step), r.median_ms, r.p99_ms,
                       r.projector == "cuda" ? std::string("-") : fmt::format("{:.0f}", r.cpu_ms),
                       r.projector == "exact" ? std::string("(reference)") : fmt::format("{:.4f}", 100 * r.rmse_rel),
                       r.projector == "exact" ? std::string("-") : fmt::format("{:.4f}", 100 * r.max_rel));
    }
    f << "\n![error vs time](xray.png)\n";
  }
  const std::string script = std::filesystem::exists("docs/benchmarks/xray.py") ? "docs/benchmarks/xray.py" : "";
  if (!script.empty()) {
    const std::string cmd = fmt::format("/usr/bin/python3 {} {} > /dev/null 2>&1", script, o.out_dir);
    if (std::system(cmd.c_str()) != 0) std::printf("xray: plot skipped (python3-matplotlib missing?)\n");
  } else {
    std::printf("xray: plot skipped (run from the repository root to find docs/benchmarks/xray.py)\n");
  }
  std::printf("xray: wrote %s/xray.md and xray.json\n", o.out_dir.c_str());
  return 0;
}

const bool registered = add("xray", "DRR projectors: ms per frame and error vs exact Siddon, CPU and GPU", run);

}  // namespace
}  // namespace pcisim::bench
