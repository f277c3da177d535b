// pcisim-model: a coronary CT angiogram into a case folder (docs/modeling.md), and synthetic CTAs
// with exact truth to test it.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "anatomy/case/case_folder.h"
#include "anatomy/heart/synthetic_heart_motion.h"
#include "anatomy/dicom/dicom_series.h"
#include "anatomy/phantom/phantom_cta.h"
#include "anatomy/volume/volume_io.h"
#include "modeling/cta/cta_pipeline.h"
#include "modeling/cta/modeling_error.h"
#include "modeling/motion/demons_motion.h"
#include "modeling/motion/synthetic_cine.h"
#include "modeling/picture/heart_fit_picture.h"
#include "modeling/picture/model_overview.h"
#include "modeling/report/model_report.h"
#include "realtime/stop_signal.h"

namespace {

using namespace pcisim;
namespace fs = std::filesystem;

Eigen::Vector3d parse_point(const std::string& s, const char* what) {
  Eigen::Vector3d p;
  char c1 = 0, c2 = 0;
  std::istringstream in(s);
  if (!(in >> p.x() >> c1 >> p.y() >> c2 >> p.z()) || c1 != ',' || c2 != ',' || !in.eof() || !p.allFinite()) {
    throw CLI::ValidationError(what, fmt::format("'{}' is not three numbers x,y,z", s));
  }
  return p;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// an option's value refused before any work: one line "pcisim-model: <option>: <what>", exit 2
struct OptionError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// --dims: three whole numbers x,y,z, each within the phantom's bounds (anatomy/phantom/phantom_cta.h)
std::array<int64_t, 3> parse_dims(const std::string& s) {
  std::array<int64_t, 3> d{};
  const std::string expected = fmt::format("expected three whole numbers x,y,z, each 1..{}, at most {} voxels in all",
                                           anatomy::kMaxPhantomCtaDim, anatomy::kMaxPhantomCtaVoxels);
  size_t at = 0;
  for (int a = 0; a < 3; ++a) {
    const size_t end = a < 2 ? s.find(',', at) : s.size();
    const std::string part = s.substr(at, end == std::string::npos ? std::string::npos : end - at);
    size_t used = 0;
    long long v = 0;
    try {
      v = std::stoll(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (end == std::string::npos || part.empty() || used != part.size() ||
        !std::isdigit(static_cast<unsigned char>(part[0])))
      throw OptionError(fmt::format("--dims: {}, got '{}'", expected, s));
    if (v < 1 || v > anatomy::kMaxPhantomCtaDim)
      throw OptionError(fmt::format("--dims: {}, got '{}' ({} along {})", expected, s, v, "xyz"[a]));
    d[a] = v;
    at = end + 1;
  }
  if (d[0] * d[1] * d[2] > anatomy::kMaxPhantomCtaVoxels)
    throw OptionError(fmt::format("--dims: {}, got '{}' ({} voxels)", expected, s, d[0] * d[1] * d[2]));
  return d;
}

// --voxel-mm: three sizes within the phantom's bounds (0.1 to 20 mm)
Eigen::Vector3d parse_voxel_mm(const std::string& s) {
  const std::string expected = fmt::format("expected three voxel sizes x,y,z in mm, each {} to {}",
                                           anatomy::kMinPhantomCtaVoxelMm, anatomy::kMaxPhantomCtaVoxelMm);
  Eigen::Vector3d p;
  char c1 = 0, c2 = 0;
  std::istringstream in(s);
  if (!(in >> p.x() >> c1 >> p.y() >> c2 >> p.z()) || c1 != ',' || c2 != ',' || !in.eof())
    throw OptionError(fmt::format("--voxel-mm: {}, got '{}'", expected, s));
  for (int a = 0; a < 3; ++a)
    if (!(p[a] >= anatomy::kMinPhantomCtaVoxelMm && p[a] <= anatomy::kMaxPhantomCtaVoxelMm))
      throw OptionError(fmt::format("--voxel-mm: {}, got '{}'", expected, s));
  return p;
}

int make_phantom(uint32_t seed, bool family, const std::string& out, const std::string& voxel, const std::string& dims,
                 const double* noise, double stenosis, bool no_coronaries, bool flip_z, bool origin_frame) {
  anatomy::PhantomCtaSpec spec;
  spec.seed = seed;
  // a family member draws its scan (voxels, matrix, noise, blur, slice order) from its seed; an
  // option given on the command line replaces that draw
  if (family) spec = anatomy::family_phantom_cta_spec(seed);
  if (!voxel.empty()) spec.spacing_mm = parse_voxel_mm(voxel);
  if (!dims.empty()) spec.dims = parse_dims(dims);
  for (int a = 0; a < 3; ++a) {
    const double extent_mm = static_cast<double>(spec.dims[a]) * spec.spacing_mm[a];
    if (extent_mm > anatomy::kMaxPhantomCtaExtentMm)
      throw OptionError(
          fmt::format("--dims, --voxel-mm: expected a field of view of at most {} mm along each axis, "
                      "got {} x {} = {} mm along {}",
                      anatomy::kMaxPhantomCtaExtentMm, spec.dims[a], spec.spacing_mm[a], extent_mm, "xyz"[a]));
  }
  if (noise) spec.noise_sigma_hu = *noise;
  spec.stenosis_fraction = stenosis;
  spec.with_coronaries = !no_coronaries;
  spec.scanner_frame = !origin_frame;
  if (flip_z) spec.direction = Eigen::Vector3d(1, 1, -1).asDiagonal();
  const auto t0 = std::chrono::steady_clock::now();
  std::printf("%s CTA %u: %lld x %lld x %lld voxels of %.2f x %.2f x %.2f mm, noise %.0f HU ...\n",
              family ? "family phantom" : "phantom", seed, (long long)spec.dims[0], (long long)spec.dims[1],
              (long long)spec.dims[2], spec.spacing_mm.x(), spec.spacing_mm.y(), spec.spacing_mm.z(),
              spec.noise_sigma_hu);
  std::fflush(stdout);
  const anatomy::PhantomCta cta = anatomy::make_phantom_cta(spec);
  std::printf("  generated in %.1f s; writing %s\n", seconds_since(t0), out.c_str());
  anatomy::write_phantom_cta(cta, out);
  modeling::write_model_overview(cta.ct, cta.truth,
                                 fmt::format("{} CTA {} - TRUTH", family ? "FAMILY PHANTOM" : "PHANTOM", seed),
                                 (fs::path(out) / "overview.png").string());
  std::printf("  aortic seed: --seed %.1f,%.1f,%.1f\n", cta.aortic_seed_mm.x(), cta.aortic_seed_mm.y(),
              cta.aortic_seed_mm.z());
  for (const anatomy::Lesion& l : anatomy::phantom_cta_lesions(cta))
    std::printf("  stenosis: %s at %.1f mm, %.0f %% (MLD %.2f of %.2f mm) over %.1f mm\n", l.branch.c_str(),
                l.position_mm, l.diameter_stenosis_pct, l.minimal_lumen_diameter_mm, l.reference_diameter_mm,
                l.length_mm);
  std::printf("done in %.1f s: ct.nrrd, truth.json, truth-lesions.json, phantom.json, overview.png\n",
              seconds_since(t0));
  return 0;
}

// pcisim-model motion: heart motion from a 4-D image sequence (issue #14, heart paper section 4)
int motion_main(int argc, char** argv) {
  CLI::App app{
      "pcisim-model motion: the heart's motion from a 4-D image sequence covering one cardiac cycle (cine MRI or\n"
      "4-D CT). Frame 0 (end-diastole) is registered to every other frame by diffeomorphic demons in a\n"
      "multi-resolution pyramid; each displacement field is sampled on a grid over the template heart and\n"
      "written as the motion file the beating heart reads (scene key heart_beat.motion_file; format in\n"
      "docs/heart.md). Frame f of F is at phase f / F. docs/heart.md, 'Motion from images'.\n\n"
      "  pcisim-model motion --sequence cine/ --out patient.motion\n"
      "  pcisim-model motion --sequence cine.nrrd --cycle-s 0.8 --out patient.motion   (one 4-D NRRD)\n"
      "  pcisim-model motion --sequence cine_dicom/ --out patient.motion   (one DICOM cine series, 3-D + time)\n"
      "  pcisim-model motion --frames f00.nrrd f01.nrrd ... --heart cases/patient1 --out "
      "cases/patient1/heart.motion\n"};
  app.name("pcisim-model motion");
  std::vector<std::string> frame_paths;
  std::string sequence, out_path, case_dir;
  double cycle_s = 60.0 / 72.0, grid_mm = 5.0;
  modeling::DemonsOptions o;
  auto* in = app.add_option_group("input", "the frames, in phase order");
  in->add_option("--frames", frame_paths, "volume files (.nrrd, .nhdr, .mha, .mhd), one per phase, frame 0 first");
  in->add_option(
      "--sequence", sequence,
      "a folder of volume files in phase order (by their numbers: frame_000.nrrd, frame_001.nrrd, ...); or a "
      "folder holding one DICOM cine series (no volume files in it): 3-D + time, its images grouped into frames by "
      "Temporal Position Identifier (0020,0100), else Trigger Time (0018,1060), in that value's order; or one "
      "4-D NRRD (.nrrd, .nhdr: sizes x y z time, the time axis's space direction none) whose time index is the "
      "frame");
  in->require_option(1);
  app.add_option("--out", out_path, "the motion file to write; a report (.json) is written beside it")->required();
  app.add_option("--heart", case_dir,
                 "a case folder whose heart the images show (its heart pose maps the template onto the images); "
                 "without it the images are in the template's frame");
  app.add_option("--cycle-s", cycle_s, "the recorded cycle's length (s)")->check(CLI::Range(0.2, 3.0));
  app.add_option("--grid-mm", grid_mm, "the motion grid's spacing over the template heart (mm)")
      ->check(CLI::Range(1.0, 20.0));
  auto* knobs = app.add_option_group("accuracy knobs", "what accuracy costs in time: docs/benchmarks/motion.md");
  knobs->add_option("--levels", o.levels, "pyramid levels, each halving the grid")->check(CLI::Range(1, 8));
  knobs->add_option("--iterations", o.iterations, "demons iterations per level")->check(CLI::Range(1, 10000));
  knobs->add_option("--field-sigma", o.field_sigma_vox, "Gaussian smoothing of the displacement field (voxels)")
      ->check(CLI::Range(0.0, 20.0));
  knobs->add_option("--max-step", o.max_step_vox, "largest update per iteration (voxels)")
      ->check(CLI::Range(0.0, 20.0));
  knobs->add_option("--threads", o.threads, "worker threads; 0 = all cores")->check(CLI::Range(0, 256));
  CLI11_PARSE(app, argc, argv);
  try {
    // a 4-D NRRD or a DICOM cine gives every frame at once; the report names them "<file or folder>[t]"
    std::vector<anatomy::Volume> frames;
    bool sequence_file = false;
    if (!sequence.empty() && !fs::is_directory(sequence)) {
      std::string ext = fs::path(sequence).extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
      if (!fs::exists(sequence)) throw std::runtime_error("--sequence: '" + sequence + "' does not exist");
      if (ext != ".nrrd" && ext != ".nhdr")
        throw std::runtime_error("--sequence: '" + sequence +
                                 "' is neither a folder of frames nor a 4-D NRRD (.nrrd, .nhdr) holding them");
      sequence_file = true;
    }
    const auto t0 = std::chrono::steady_clock::now();
    if (sequence_file) {
      frames = anatomy::read_nrrd_sequence(sequence, true);
      for (size_t t = 0; t < frames.size(); ++t) frame_paths.push_back(fmt::format("{}[{}]", sequence, t));
    } else {
      bool dicom_cine = false;
      if (!sequence.empty()) {
        for (const auto& e : fs::directory_iterator(sequence)) {
          const std::string ext = e.path().extension().string();
          if (e.is_regular_file() && (ext == ".nrrd" || ext == ".nhdr" || ext == ".mha" || ext == ".mhd"))
            frame_paths.push_back(e.path().string());
        }
        // a folder without volume files is a DICOM folder, as --ct's folder is: one cine series
        dicom_cine = frame_paths.empty();
        if (dicom_cine) {
          try {
            frames = anatomy::read_dicom_cine(sequence);
          } catch (const anatomy::DicomError& e) {
            throw std::runtime_error(fmt::format(
                "--sequence: '{}' holds no volume files (.nrrd, .nhdr, .mha, .mhd), so it was read as a DICOM cine: {}",
                sequence, e.what()));
          }
          for (size_t t = 0; t < frames.size(); ++t) frame_paths.push_back(fmt::format("{}[{}]", sequence, t));
        } else {
          frame_paths = modeling::order_frame_files(frame_paths);
          if (frame_paths.size() < 2)
            throw std::runtime_error(fmt::format("--sequence: '{}' holds {} volume files; a cycle needs at least 2",
                                                 sequence, frame_paths.size()));
        }
      }
      if (!dicom_cine)
        for (const std::string& path : frame_paths) frames.push_back(anatomy::read_volume(path, true));
    }
    anatomy::HeartPose pose;
    if (!case_dir.empty()) pose = anatomy::read_case(case_dir).heart;
    const anatomy::MotionGrid grid = anatomy::template_motion_grid(grid_mm * 1e-3);
    std::printf("%zu frames of %lld x %lld x %lld voxels; demons %d levels x %d iterations, field sigma %.2f voxels\n",
                frames.size(), (long long)frames[0].dims[0], (long long)frames[0].dims[1], (long long)frames[0].dims[2],
                o.levels, o.iterations, o.field_sigma_vox);
    std::fflush(stdout);
    std::vector<modeling::MotionFrameReport> reports;
    const anatomy::HeartMotion motion = modeling::recover_heart_motion(
        frames, cycle_s, grid, pose, o, &reports, [&](const modeling::MotionFrameReport& r) {
          std::printf("  frame %d/%zu: %.1f s, RMS difference to frame 0 %.4g -> %.4g\n", r.frame, frames.size() - 1,
                      r.seconds, r.rms_before, r.rms_after);
          std::fflush(stdout);
        });
    motion.write(out_path);
    // the report: what was asked and what each frame took; a non-finite figure is null (not JSON otherwise)
    auto number = [](double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : std::string("null"); };
    auto quoted = [](const std::string& t) {
      std::string q = "\"";
      for (char ch : t) {
        if (ch == '"' || ch == '\\') q += '\\';
        if (static_cast<unsigned char>(ch) >= 0x20) q += ch;
      }
      return q + "\"";
    };
    std::ofstream report(out_path + ".json");
    report << "{\n  \"frames\": [";
    for (size_t i = 0; i < frame_paths.size(); ++i) report << (i ? ", " : "") << quoted(frame_paths[i]);
    report << "],\n  \"heart_case\": " << (case_dir.empty() ? std::string("null") : quoted(case_dir))
           << ",\n  \"cycle_s\": " << number(cycle_s) << ",\n  \"grid_mm\": " << number(grid_mm)
           << ",\n  \"levels\": " << o.levels << ",\n  \"iterations\": " << o.iterations
           << ",\n  \"field_sigma_vox\": " << number(o.field_sigma_vox)
           << ",\n  \"max_step_vox\": " << number(o.max_step_vox) << ",\n  \"threads\": " << o.threads
           << ",\n  \"per_frame\": [";
    for (size_t i = 0; i < reports.size(); ++i)
      report << (i ? ",\n" : "\n")
             << fmt::format(
                    "    {{\"frame\": {}, \"seconds\": {}, \"metric\": {}, \"rms_before\": {}, \"rms_after\": {}}}",
                    reports[i].frame, number(reports[i].seconds), number(reports[i].metric),
                    number(reports[i].rms_before), number(reports[i].rms_after));
    report << "\n  ]\n}\n";
    report.close();
    if (!report) throw std::runtime_error("cannot write " + out_path + ".json");
    std::printf("done in %.1f s: %s (%d x %d x %d grid, %.1f mm), %s.json\n", seconds_since(t0), out_path.c_str(),
                grid.dims.x(), grid.dims.y(), grid.dims.z(), grid_mm, out_path.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pcisim-model motion: %s\n", e.what());
    return 1;
  }
}

// pcisim-model cine: a synthetic cine sequence of the template heart with its exact motion
int cine_main(int argc, char** argv) {
  CLI::App app{
      "pcisim-model cine: writes a synthetic cine sequence of the template heart moving by the built-in contraction\n"
      "(docs/heart.md): bright blood, dark myocardium, epicardial fat, partial volume and noise, one float NRRD per\n"
      "phase (frame_000.nrrd ...), and the exact motion beside it (truth.motion), to test `pcisim-model motion`;\n"
      "with --nrrd4d also the whole sequence as one 4-D NRRD (x y z time).\n\n"
      "  pcisim-model cine --out out/cine && pcisim-model motion --sequence out/cine --out out/recovered.motion\n"
      "  pcisim-model cine --out out/cine --nrrd4d out/cine.nrrd && pcisim-model motion --sequence out/cine.nrrd "
      "--out out/recovered.motion\n"};
  app.name("pcisim-model cine");
  std::string out_dir, nrrd4d;
  modeling::CineSpec spec;
  double voxel_mm = spec.voxel_mm.x();
  app.add_option("--out", out_dir, "the folder to write (created)")->required();
  app.add_option("--frames", spec.frames, "frames over one cycle")->check(CLI::Range(2, 200));
  app.add_option("--voxel-mm", voxel_mm, "voxel size (mm, isotropic)")->check(CLI::Range(0.5, 10.0));
  app.add_option("--slice-mm", spec.slice_thickness_mm, "slice thickness along z (mm); 0: the voxel's")
      ->check(CLI::Range(0.0, 20.0));
  app.add_option("--noise", spec.noise_sigma, "Gaussian noise sigma (intensities 0..1)")->check(CLI::Range(0.0, 1.0));
  app.add_option("--tags", spec.tag_amplitude, "amplitude of a tag pattern carried by the tissue (0: plain cine)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--seed", spec.seed, "noise seed");
  app.add_option("--nrrd4d", nrrd4d,
                 "also write the frames as one 4-D NRRD (.nrrd, float, sizes x y z time), outside --out's folder "
                 "(which `pcisim-model motion --sequence` reads as frames)");
  CLI11_PARSE(app, argc, argv);
  spec.voxel_mm = Eigen::Vector3d::Constant(voxel_mm);
  if (spec.slice_thickness_mm > 0) spec.voxel_mm.z() = std::max(voxel_mm, spec.slice_thickness_mm);
  try {
    anatomy::SyntheticMotionSpec truth_spec;
    truth_spec.frames = spec.frames;
    const anatomy::HeartMotion truth = anatomy::make_synthetic_heart_motion(truth_spec);
    if (fs::exists(out_dir)) {
      for (const auto& e : fs::directory_iterator(out_dir)) {
        const std::string ext = e.path().extension().string();
        if (ext == ".nrrd" || ext == ".nhdr" || ext == ".mha" || ext == ".mhd")
          throw std::runtime_error("--out: '" + out_dir + "' already holds volume files (" +
                                   e.path().filename().string() +
                                   "); a sequence read back from it would mix two runs: choose an empty folder");
      }
    }
    if (!nrrd4d.empty()) {
      std::string ext = fs::path(nrrd4d).extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
      if (ext != ".nrrd") throw std::runtime_error("--nrrd4d: '" + nrrd4d + "' must end in .nrrd");
      // in the frames' folder it would be read as one more frame (and refused: it has no number)
      auto folder = [](const fs::path& p) {
        const fs::path c = fs::weakly_canonical(fs::absolute(p));
        return c.has_filename() ? c : c.parent_path();  // "out/cine/" is "out/cine"
      };
      if (folder(nrrd4d).parent_path() == folder(out_dir))
        throw std::runtime_error("--nrrd4d: '" + nrrd4d + "' lies in --out's folder, which holds the frames only: " +
                                 "write it beside the folder");
    }
    const auto t0 = std::chrono::steady_clock::now();
    fs::create_directories(out_dir);
    std::vector<anatomy::Volume> all;  // kept for --nrrd4d only
    for (int f = 0; f < spec.frames; ++f) {
      anatomy::Volume v = modeling::render_synthetic_cine_frame(truth, spec, f);
      anatomy::write_nrrd(v, (fs::path(out_dir) / fmt::format("frame_{:03d}.nrrd", f)).string());
      std::printf("  frame %d/%d written (%.1f s)\n", f + 1, spec.frames, seconds_since(t0));
      std::fflush(stdout);
      if (!nrrd4d.empty()) all.push_back(std::move(v));
    }
    truth.write((fs::path(out_dir) / "truth.motion").string());
    if (!nrrd4d.empty()) {
      if (fs::path(nrrd4d).has_parent_path()) fs::create_directories(fs::path(nrrd4d).parent_path());
      anatomy::write_nrrd_sequence(all, nrrd4d);
    }
    std::printf("done in %.1f s: %d frames and truth.motion in %s%s\n", seconds_since(t0), spec.frames, out_dir.c_str(),
                nrrd4d.empty() ? "" : (", the 4-D sequence in " + nrrd4d).c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pcisim-model cine: %s\n", e.what());
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  // no loop watches a flag here: SIGINT/SIGTERM end the run at once, saying so
  pcisim::realtime::install_stop_signals("pcisim-model", "working");
  if (argc > 1 && std::string(argv[1]) == "motion") return motion_main(argc - 1, argv + 1);
  if (argc > 1 && std::string(argv[1]) == "cine") return cine_main(argc - 1, argv + 1);
  CLI::App app{
      "pcisim-model: turns a patient's coronary CT angiogram (CTA) into a pcisim case folder: the contrast-filled\n"
      "lumen is segmented from one seed in the ascending aorta, clipped to the aorta and the coronary trees,\n"
      "its centerlines traced with their branches, the radius measured on every cross-section, the lumen lofted\n"
      "and the branches named (LM, LAD, LCx, RCA, diagonals, marginals); the template heart is placed under the\n"
      "tree and fitted to the CT's heart (heart.node, heart-fit.png). docs/modeling.md describes each stage.\n\n"
      "  pcisim-model --ct ct.nrrd --seed 12.5,-140,-95 --out cases/patient1\n"
      "  pcisim-model --make-phantom-cta --seed 3 --out cta3   (a synthetic CTA with its truth)\n"
      "  pcisim-model motion --help   (the heart's motion from a 4-D image sequence)\n"
      "  pcisim-model cine --help     (a synthetic cine sequence with its exact motion, to test it)\n"};
  std::string ct_path, out_dir, voxel, dims;
  std::vector<std::string> seeds;
  bool make_phantom_cta = false, no_coronaries = false, flip_z = false, origin_frame = false;
  double noise_hu = 25, stenosis = -1, memory_gb = 4;
  int threads = 0;
  pcisim::modeling::CtaPipelineOptions o;
  app.add_option("--ct", ct_path,
                 "the CTA: a volume file (.nrrd, .nhdr, .mha, .mhd) or a folder holding one DICOM series; HU, with "
                 "its spacing");
  app.add_option("--seed", seeds,
                 "x,y,z in millimetres in the CT's physical (LPS) frame; the first inside the ascending aorta, further "
                 "ones (an ostium, a distal point) keep the vessel they sit in. With --make-phantom-cta: the phantom's "
                 "number")
      ->required();
  app.add_option("--out", out_dir, "the folder to write (created): the case, model-report.json, overview.png")
      ->required();
  app.add_option("--threads", threads, "worker threads; 0 = all cores")->check(CLI::Range(0, 256));
  app.add_option("--memory-gb", memory_gb, "refuse a CT whose pipeline would need more memory than this (GB)")
      ->check(CLI::Range(0.1, 1024.0));
  auto* knobs = app.add_option_group("accuracy knobs", "what accuracy costs in time: docs/benchmarks/model.md");
  knobs
      ->add_option("--level-set-iterations", o.segmentation.level_set.iterations,
                   "iterations of the 3-D level set after the region growing [heart eq 1]; 0 skips it")
      ->check(CLI::Range(0, 10000));
  knobs
      ->add_option("--level-set-curvature", o.segmentation.level_set.curvature_weight,
                   "weight of the mean-curvature term of that level set (smooths, and thins narrow vessels)")
      ->check(CLI::Range(0.0, 10.0));
  knobs
      ->add_option("--max-gap-mm", o.segmentation.bridging.max_gap_mm,
                   "the widest gap in a vessel's contrast (a stenosis too tight to see) bridged to the vessel beyond "
                   "it (mm); 0 bridges none")
      ->check(CLI::Range(0.0, 30.0));
  knobs
      ->add_option("--section-spacing-mm", o.spline.sample_spacing_mm,
                   "distance between cross-sections along each centerline (mm)")
      ->check(CLI::Range(0.1, 5.0));
  knobs
      ->add_option("--knot-spacing-mm", o.spline.knot_spacing_mm,
                   "B-spline knot spacing along each branch (mm); larger is smoother")
      ->check(CLI::Range(0.5, 50.0));
  knobs->add_option("--radius-iterations", o.radius.iterations, "iterations of each 2-D level set [heart eq 2]")
      ->check(CLI::Range(2, 10000));
  double lumen_spacing_mm = o.stitched_lumen.spacing_m * 1e3;
  // finer than 0.1 mm the stitched lumen of a phantom CTA passes the 8 M triangles a case's
  // lumen.stl may hold (anatomy/case/case_limits.h: 7.2 M at 0.1 mm), so the case would be refused
  knobs
      ->add_option("--lumen-spacing-mm", lumen_spacing_mm,
                   "grid spacing of the stitched lumen surface (mm); finer than 0.1 mm the lumen would exceed "
                   "the triangles a case may hold")
      ->check(CLI::Range(0.1, 2.0));
  bool tubes = false;
  knobs->add_flag("--lumen-tubes", tubes, "lumen.stl as one closed tube per branch instead of one stitched surface");
  bool robust_fill = false;
  knobs->add_flag("--robust-fill", robust_fill,
                  "the lumen fill on the CT smoothed by 0.5 mm from the start (no noise sponges through a chamber or "
                  "the myocardium near the threshold); without it the pipeline fills the smoothed CT again only when "
                  "the first fill made such a sponge at the aortic root; docs/modeling.md");
  bool no_tube_growth = false;
  knobs->add_flag("--no-tube-growth", no_tube_growth,
                  "do not follow thin vessels along bright tubes (vesselness) past the lower threshold: faster, loses "
                  "distal vessels whose contrast fades; docs/modeling.md");
  bool no_heart_fit = false;
  knobs->add_flag("--no-heart-fit", no_heart_fit,
                  "keep the template heart as placed under the vessels (no elastic fit to the CT's heart, no "
                  "heart.node, no heart-fit.png)");
  auto* ph = app.add_option_group("phantom", "synthetic CTAs with exact truth");
  ph->add_flag("--make-phantom-cta", make_phantom_cta,
               "write a synthetic CTA (ct.nrrd), its true centerlines and radii (truth.json), what was drawn "
               "(phantom.json) and a picture; --seed N picks the phantom");
  ph->add_option("--voxel-mm", voxel, "voxel size x,y,z (mm), each 0.1 to 20; default 0.4,0.4,0.6");
  ph->add_option("--dims", dims,
                 "voxels along x,y,z, each 1..4096, at most 2^28 in all and 1000 mm of field along each axis; default "
                 "512,512,250");
  auto* noise_option = ph->add_option("--noise-hu", noise_hu, "noise sigma (HU); default 25 (with --family: drawn)")
                           ->check(CLI::Range(0.0, 200.0));
  ph->add_option("--stenosis", stenosis, "diameter reduction of the stenosis (0..0.99); default drawn 0.5..0.8")
      ->check(CLI::Range(0.0, 0.99));
  bool family = false;
  ph->add_flag("--family", family,
               "a member of the varied phantom family (issue #30): the seed also draws the scan (voxels 0.3..0.8 mm, "
               "anisotropic, noise 15..45 HU, slice order), the heart's shape, chambers, valve, right-ventricular "
               "wall, left atrial appendage, crossing veins, calcium blooming, a stent, small side branches; seeds "
               "from 1001 are the held-out split (docs/benchmarks/model.md). --voxel-mm, --dims and --noise-hu "
               "replace what it draws");
  ph->add_flag("--no-coronaries", no_coronaries, "a CTA without coronary arteries");
  ph->add_flag("--flip-z", flip_z, "slices stored feet-first (direction diag(1, 1, -1))");
  ph->add_flag("--origin-frame", origin_frame, "the heart centre at the origin instead of scanner coordinates");
  CLI11_PARSE(app, argc, argv);
  o.stitched_lumen.spacing_m = lumen_spacing_mm * 1e-3;
  o.stitched = !tubes;
  o.heart_fit.enabled = !no_heart_fit;
  if (robust_fill) o.segmentation.smoothing_mm = 0.5;
  o.segmentation.tubes.enabled = !no_tube_growth;
  o.threads = threads;
  o.segmentation.bridging.enabled = o.segmentation.bridging.max_gap_mm > 0;

  try {
    if (make_phantom_cta) {
      if (seeds.size() != 1) throw CLI::ValidationError("--seed", "--make-phantom-cta takes one --seed N");
      unsigned long n = 0;
      try {
        size_t used = 0;
        n = std::stoul(seeds[0], &used);
        if (used != seeds[0].size() || n > 0xffffffffu) throw std::invalid_argument("");
      } catch (const std::exception&) {
        throw CLI::ValidationError("--seed", fmt::format("'{}' is not a phantom number", seeds[0]));
      }
      const bool noise_given = noise_option->count() > 0 || !family;
      return make_phantom(static_cast<uint32_t>(n), family, out_dir, voxel, dims, noise_given ? &noise_hu : nullptr,
                          stenosis, no_coronaries, flip_z, origin_frame);
    }
    if (ct_path.empty()) throw CLI::ValidationError("--ct", "the CTA to model is required (or --make-phantom-cta)");
    std::vector<Eigen::Vector3d> seed_mm;
    for (const auto& s : seeds) seed_mm.push_back(parse_point(s, "--seed"));

    const auto t0 = std::chrono::steady_clock::now();
    std::printf("reading %s ...\n", ct_path.c_str());
    std::fflush(stdout);
    anatomy::Volume ct = fs::is_directory(ct_path) ? anatomy::read_dicom_series(ct_path)
                                                   : anatomy::read_volume(ct_path, /*require_spacing=*/true);
    std::printf("  %lld x %lld x %lld voxels of %.2f x %.2f x %.2f mm (%.1f s)\n", (long long)ct.dims[0],
                (long long)ct.dims[1], (long long)ct.dims[2], ct.spacing_mm.x(), ct.spacing_mm.y(), ct.spacing_mm.z(),
                seconds_since(t0));
    o.memory_limit_gb = memory_gb;
    const auto t1 = std::chrono::steady_clock::now();
    modeling::CtaModel m = modeling::build_cta_model(ct, seed_mm, o, [](const modeling::StageReport& r, bool done) {
      if (!done) {
        std::printf("%-13s ...", r.name.c_str());
      } else {
        std::string figs;
        for (const auto& [k, v] : r.figures) figs += fmt::format("{}{} {:g}", figs.empty() ? "" : ", ", k, v);
        std::printf(" %.2f s  (%s)\n", r.seconds, figs.c_str());
      }
      std::fflush(stdout);
    });
    const double model_s = seconds_since(t1);
    std::printf("model built in %.1f s; writing %s ...\n", model_s, out_dir.c_str());
    std::fflush(stdout);
    m.model.name = fs::path(out_dir).filename().string();
    if (m.model.name.empty()) m.model.name = fs::path(out_dir).parent_path().filename().string();
    m.model.ct = std::move(ct);
    anatomy::write_case(m.model, out_dir);
    modeling::write_model_overview(*m.model.ct, m.model.vessels, m.model.name + " - MODEL",
                                   (fs::path(out_dir) / "overview.png").string());
    if (m.model.heart_vertices_m.cols() > 0)
      modeling::write_heart_fit_picture(*m.model.ct, anatomy::template_heart_mesh(), m.model.heart,
                                        anatomy::template_heart_mesh().vertices_m, m.model.heart_vertices_m,
                                        m.model.name + " - HEART", (fs::path(out_dir) / "heart-fit.png").string());
    modeling::write_model_report((fs::path(out_dir) / "model-report.json").string(), ct_path, *m.model.ct, seed_mm, m,
                                 model_s);
    for (const anatomy::Lesion& l : m.model.lesions)
      std::printf("lesion: %s at %.1f mm, %.0f %% diameter stenosis (MLD %.2f of %.2f mm) over %.1f mm\n",
                  l.branch.c_str(), l.position_mm, l.diameter_stenosis_pct, l.minimal_lumen_diameter_mm,
                  l.reference_diameter_mm, l.length_mm);
    std::printf(
        "done: %zu branches, %zu lesions; case folder, model-report.json, overview.png%s in %s (%.1f s in all, peak "
        "%.0f MiB)\n",
        m.model.vessels.branches.size(), m.model.lesions.size(),
        m.model.heart_vertices_m.cols() > 0 ? " and heart-fit.png" : "", out_dir.c_str(), seconds_since(t0),
        modeling::peak_memory_mib());
    return 0;
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pcisim-model: %s\n", e.what());
    return 2;
  }
}
