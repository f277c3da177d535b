#pragma once
// Synthetic cine-MRI-like 4-D sequences of the template heart moved by a known motion (issue #14):
// bright-blood (bSSFP-like) intensities on a 0..1 scale, so that a registration of the frames can
// be checked against exact truth at every point and phase. Frame f is the template at phase
// f / frames, every voxel sampled by inverting the motion (where did this tissue rest?).
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "anatomy/heart/heart_motion.h"
#include "anatomy/volume/volume.h"

namespace pcisim::modeling {

enum class CineTissue { kBlood, kMyocardium, kFat, kOther };

// the template heart's tissue at a rest point (patient LPS, m): LV or RV cavity -> blood; inside
// the epicardium -> myocardium; within fat_mm radially outside it -> fat; else other
CineTissue template_tissue(const Eigen::Vector3d& rest_m, double fat_mm);

// a tissue's noise-free intensity (blood 1.0, myocardium 0.25, fat 0.85, other 0.4)
float cine_intensity(CineTissue tissue);

struct CineSpec {
  int frames = 20;                          // over one cycle, frame f at phase f / frames
  Eigen::Vector3d voxel_mm{1.5, 1.5, 1.5};  // spacing of the grid
  double slice_thickness_mm = 0.0;          // 0: none; > 0: box profile along z of that thickness
  double margin_mm = 12.0;                  // around the template heart's bounding box
  double fat_mm = 3.0;                      // epicardial fat layer
  double noise_sigma = 0.03;                // gaussian, added to every voxel
  uint64_t seed = 1;                        // with the frame index, seeds that frame's noise
  int supersample = 2;                      // samples per axis in a voxel (partial volume)
  // a pattern carried by the tissue, like myocardial tagging: intensity * (1 + tag_amplitude *
  // sin(x / w) sin(y / w) sin(z / w)) of the rest point, w = tag_wavelength_mm / 2 pi. 0: plain cine,
  // whose uniform tissue hides motion along its edges (the aperture problem); the tags show it
  double tag_amplitude = 0.0;
  double tag_wavelength_mm = 8.0;
};

// "" when usable, else a message naming the field, e.g. "frames: must be 2..200, got 1"
std::string validate(const CineSpec& spec);

struct CineSequence {
  std::vector<anatomy::Volume> frames;  // float32, identity direction, patient LPS mm
  double cycle_s = 0;
};

// the rest point r with r + truth.displacement_m(r, phase) = x_m (fixed-point iteration from
// x - d(x), at most 30 steps, stopping when a step is below 1e-7 m)
Eigen::Vector3d cine_rest_point_m(const anatomy::HeartMotion& truth, const Eigen::Vector3d& x_m, double phase);

// throws std::invalid_argument with validate's message; deterministic (same spec, same bits)
CineSequence render_synthetic_cine(const anatomy::HeartMotion& truth, const CineSpec& spec);
// frame f (0 <= f < spec.frames) alone, bit-identical to render_synthetic_cine's frame f
anatomy::Volume render_synthetic_cine_frame(const anatomy::HeartMotion& truth, const CineSpec& spec, int frame);

// dir/frame_000.nrrd, frame_001.nrrd, ... (float32 NRRD) and nothing else; creates dir
void write_cine(const CineSequence& sequence, const std::string& dir);

}  // namespace pcisim::modeling
