// pcisim-dataset: labelled fluoroscopy datasets, made headless and as fast as the machine goes.
// Arguments are parsed by hand so the tool builds wherever the library does (the GPU machine has
// no CLI11).
#include <fmt/format.h>

#include <cstdint>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "dataset/run/dataset_folder.h"
#include "dataset/run/dataset_run.h"
#include "dataset/run/input_checks.h"
#include "dataset/sample/sample_plan.h"
#include "json/json_reader.h"
#include "realtime/stop_signal.h"

namespace {

using namespace pcisim::dataset;

constexpr const char* kHelp = R"(pcisim-dataset: labelled fluoroscopy datasets from randomised simulations.

  pcisim-dataset --spec FILE --out DIR [--shard I/N] [--jobs J] [--max-samples K]
  pcisim-dataset --merge --spec FILE --out DIR
  pcisim-dataset --check --spec FILE
  pcisim-dataset --print-spec
  pcisim-dataset --digest SAMPLE_DIR   (the digest its manifest line records)

Each sample draws its anatomy, C-arm, dose, contrast, heart rate, wire and instrument motion
from the spec's distributions (seeded by the spec's seed and the sample's number), runs the
scene headless and not paced to real time, and writes its frames (16-bit PNG) with labels: the
wire's 3-D and 2-D polylines, tip and keypoints, every centerline with its branch, the contrast
mask and branch label images (PNG), the projection and the simulation's parameters. The layout,
every key of the spec and the labels' exact definitions are in docs/dataset.md.

  --spec FILE      the dataset spec (JSON with comments); --print-spec prints an example
  --out DIR        the dataset folder: created, or resumed when it holds the same spec
  --shard I/N      make only samples i with i % N == I (0 <= I < N), for parallel jobs; merge
                   with --merge once every shard has finished (scripts/dataset-slurm does both)
  --jobs J         make J samples at once, each on its own thread (default 1; the same files
                   whatever J: a sample depends on its number alone). On a machine whose
                   projector is the GPU, one job per CPU core keeps it busy
  --max-samples K  stop after K samples (made or failed; a later run resumes)
  --merge          write DIR/manifest.json and DIR/coco.json from every shard's lists
  --check          check the spec (every key, every varied value at its extremes, the scripts,
                   projector and cases it names) and exit

Without --shard the run merges by itself when it has made every sample. Interrupting it
(Ctrl-C) finishes the sample in progress; running the same command again resumes, never
redoing or duplicating a sample. A sample that fails is recorded with its seed and error in
DIR/shards/failed-*.jsonl and the run goes on.

A run stops (the sample in progress removed, nothing half-written listed) when the folder
cannot be written or memory runs out; a second process on the same shard is refused.

Before the first sample every key of the spec is checked, and so is what it names: each
trainee script is read and parsed, the projector each sample would take is probed (CUDA needs a
GPU that answers, GL a context), each case folder is read and fitted to the scene.

Exit status: 0 done (failed samples included, and counted, as long as one was made), 2 bad
arguments or spec (or what it names), 3 merge asked before every sample is made, 4 the disk is
full (resume when there is space), 5 interrupted, 6 every sample this run tried failed, 1 any
other error (the folder cannot be written, ...). SIGINT/SIGTERM while the spec is checked ends
the program at once (128 + the signal); once samples run, the first finishes the sample in
progress and the second ends the program at once.
)";

constexpr const char* kExampleSpec = R"({
  // 100 samples of 10 frames on the built-in scene's phantoms, random C-arm and dose
  "name": "example",
  "samples": 100,
  "frames_per_sample": 10,
  "seed": 1,
  "scene": "built-in",
  "projector": "auto",
  "anatomy": { "phantom_seeds": { "integers": [1, 4] } },
  "warmup_s": { "uniform": [2, 5] },
  "driver": { "kind": "random_walk", "hold_s": 0.4,
              "insert_rate_mm_s": { "uniform": [-2, 10] },
              "rotate_rate_deg_s": { "uniform": [-90, 90] }, "max_insertion_mm": 70 },
  "contrast": { "probability": 0.7, "start_s": { "uniform": [-1.5, 0.5] } },
  "labels": { "mask_min_line_integral": 0.05, "wire_keypoints": 16, "wire_keypoint_span_mm": 120 },
  "vary": {
    "effects.xray.primary_deg": { "uniform": [-45, 45] },
    "effects.xray.secondary_deg": { "uniform": [-30, 30] },
    "effects.xray.sid_mm": { "uniform": [950, 1200] },
    "effects.xray.pulse_rate_fps": { "choice": [7.5, 15, 30] },
    "effects.xray.blur_sigma_px": { "uniform": [0.4, 1.2] },
    "effects.detector_noise.photons_per_pixel": { "log_uniform": [300, 5000] },
    "effects.heart_beat.rate_bpm": { "uniform": [55, 100] },
    "effects.guidewire.tip_angle_deg": { "uniform": [20, 70] },
    "effects.contrast.injection_ml": { "uniform": [4, 10] }
  }
}
)";

struct Args {
  std::string spec, out;
  Shard shard;
  bool shard_given = false, merge = false, check = false;
  int64_t max_samples = -1;
  int jobs = 1;
};

[[noreturn]] void usage(const std::string& what) {
  std::fprintf(stderr, "pcisim-dataset: %s (see --help)\n", what.c_str());
  std::exit(2);
}

// the value of `flag` as a whole number in [lo, hi], or the usage error naming it
int64_t whole_number(const std::string& flag, const std::string& v, int64_t lo, int64_t hi) {
  int64_t n = 0;
  size_t used = 0;
  try {
    n = std::stoll(v, &used);
  } catch (...) {
    used = 0;
  }
  if (used == 0 || used != v.size() || n < lo || n > hi)
    usage(fmt::format("{}: expected a whole number in [{}, {}], got \"{}\"", flag, lo, hi, v));
  return n;
}

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(k + " needs a value");
      return argv[++i];
    };
    if (k == "--help" || k == "-h") {
      std::fputs(kHelp, stdout);
      std::exit(0);
    } else if (k == "--digest") {
      // a sample folder's digest, as its manifest line records it (checks a copy is whole)
      const std::string dir = value();
      try {
        std::printf("%s\n", DatasetFolder::folder_digest(dir).c_str());
      } catch (const std::exception& e) {
        std::fprintf(stderr, "pcisim-dataset: --digest %s: %s\n", dir.c_str(), e.what());
        std::exit(1);
      }
      std::exit(0);
    } else if (k == "--print-spec") {
      std::fputs(kExampleSpec, stdout);
      std::exit(0);
    } else if (k == "--spec") {
      a.spec = value();
    } else if (k == "--out") {
      a.out = value();
    } else if (k == "--merge") {
      a.merge = true;
    } else if (k == "--check") {
      a.check = true;
    } else if (k == "--max-samples") {
      a.max_samples = whole_number(k, value(), 0, INT64_MAX);
    } else if (k == "--jobs") {
      a.jobs = static_cast<int>(whole_number(k, value(), 1, 256));
    } else if (k == "--shard") {
      const std::string v = value();
      const size_t slash = v.find('/');
      try {
        if (slash == std::string::npos) throw 0;
        size_t used = 0;
        a.shard.index = std::stoi(v.substr(0, slash), &used);
        if (used != slash) throw 0;
        a.shard.count = std::stoi(v.substr(slash + 1), &used);
        if (used != v.size() - slash - 1) throw 0;
      } catch (...) {
        usage("--shard: expected I/N, two whole numbers, got \"" + v + "\"");
      }
      if (a.shard.count < 1 || a.shard.index < 0 || a.shard.index >= a.shard.count)
        usage("--shard " + v + ": expected 0 <= I < N");
      a.shard_given = true;
    } else {
      usage("unknown argument \"" + k + "\"");
    }
  }
  if (a.spec.empty()) usage("--spec FILE is needed");
  if (!a.check && a.out.empty()) usage("--out DIR is needed");
  if (a.merge && a.shard_given) usage("--merge goes without --shard (it merges every shard)");
  return a;
}

// where the time went, as shares of the stages' sum
void print_stages(const StageTimes& t) {
  const double sum = t.anatomy_s + t.world_s + t.beat_s + t.physics_s + t.projection_s + t.overlay_s + t.noise_s +
                     t.labels_s + t.write_s;
  if (sum <= 0) return;
  auto pct = [&](double x) { return 100.0 * x / sum; };
  std::fprintf(stderr,
               "pcisim-dataset: stages: anatomy %.0f %%, world %.0f %%, beat %.0f %%, physics %.0f %%, projection "
               "%.0f %%, overlays %.0f %%, noise %.0f %%, labels %.0f %%, writing %.0f %%\n",
               pct(t.anatomy_s), pct(t.world_s), pct(t.beat_s), pct(t.physics_s), pct(t.projection_s), pct(t.overlay_s),
               pct(t.noise_s), pct(t.labels_s), pct(t.write_s));
}

}  // namespace

int main(int argc, char** argv) {
  // until the samples run, SIGINT/SIGTERM end the process at once (the up-front checks read every case)
  pcisim::realtime::install_stop_signals("pcisim-dataset");
  const Args a = parse(argc, argv);
  DatasetSpec spec;
  try {
    spec = load_dataset_spec(a.spec);
    // the scripts, the projector and the cases, before any sample (a merge runs none)
    if (!a.merge) check_spec_inputs(spec);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pcisim-dataset: %s\n", e.what());
    return 2;
  }
  if (a.check) {
    std::printf("%s: ok: %lld samples of %d frames, %zu varied values, projector %s\n", a.spec.c_str(),
                static_cast<long long>(spec.samples), spec.frames_per_sample, spec.vary.size(),
                spec.projector == "auto" ? (gpu_projector_available() ? "auto (cuda)" : "auto (the scene's)")
                                         : spec.projector.c_str());
    return 0;
  }
  try {
    if (a.merge) {
      const auto m = merge_dataset(a.out, spec);
      std::fprintf(stderr, "pcisim-dataset: merged %s: %lld samples, %lld frames, %zu failed\n", a.out.c_str(),
                   static_cast<long long>(m["samples_made"].get<int64_t>()),
                   static_cast<long long>(m["frames"].get<int64_t>()), m["failed"].size());
      return 0;
    }
    // from now a signal finishes the sample in progress (a second one ends the process at once)
    pcisim::realtime::mark_running();
    RunOptions o;
    o.out_dir = a.out;
    o.shard = a.shard;
    o.max_samples = a.max_samples;
    o.jobs = a.jobs;
    o.stop = &pcisim::realtime::stop_flag();
    const RunReport r = run_dataset(spec, o, std::cerr);
    print_stages(r.times);
    if (r.disk_full) {
      std::fprintf(stderr,
                   "pcisim-dataset: the disk is full (%s): %lld samples made this run, %lld left; nothing half-written "
                   "is listed. Free space and run the same command to resume\n",
                   r.disk_full_what.c_str(), static_cast<long long>(r.made), static_cast<long long>(r.remaining));
      return 4;
    }
    if (!r.stop_error.empty()) {
      std::fprintf(stderr,
                   "pcisim-dataset: stopped: %s: %lld samples made this run, %lld left; nothing half-written is "
                   "listed. Run the same command to resume once that is fixed\n",
                   r.stop_error.c_str(), static_cast<long long>(r.made), static_cast<long long>(r.remaining));
      return 1;
    }
    if (r.interrupted) {
      std::fprintf(stderr, "pcisim-dataset: interrupted: %lld samples left; run the same command to resume\n",
                   static_cast<long long>(r.remaining));
      return 5;
    }
    if (r.remaining == 0 && a.shard.count == 1) {
      const auto m = merge_dataset(a.out, spec);
      std::fprintf(stderr, "pcisim-dataset: %s: %lld samples, %lld frames, %zu failed (manifest.json, coco.json)\n",
                   a.out.c_str(), static_cast<long long>(m["samples_made"].get<int64_t>()),
                   static_cast<long long>(m["frames"].get<int64_t>()), m["failed"].size());
    }
    // a run that made nothing of what it tried is no success, whatever was recorded
    if (r.made == 0 && r.failed > 0) {
      std::fprintf(stderr,
                   "pcisim-dataset: every sample this run tried failed (%lld; their errors are above and in "
                   "%s/shards/failed-*.jsonl)\n",
                   static_cast<long long>(r.failed), a.out.c_str());
      return 6;
    }
    return 0;
  } catch (const pcisim::json::JsonError& e) {
    std::fprintf(stderr, "pcisim-dataset: %s\n", e.what());
    return 2;
  } catch (const DiskFull& e) {
    std::fprintf(stderr, "pcisim-dataset: the disk is full (%s); free space and run the same command\n", e.what());
    return 4;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pcisim-dataset: %s\n", e.what());
    return std::string(e.what()).find("not made yet") != std::string::npos ? 3 : 1;
  }
}
