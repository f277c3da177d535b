#pragma once
// The built-in motion sequence: a kinematic left-ventricle-centred contraction of the template
// heart (docs/heart.md). End-diastole at phase 0; systole, then rapid filling, then diastasis.
#include "anatomy/heart/heart_motion.h"

namespace pcisim::anatomy {

struct SyntheticMotionSpec {
  int frames = 20;
  double cycle_s = 60.0 / 72.0;
  double grid_spacing_m = 0.005;
  double systole_fraction = 0.35;         // of the cycle, end-diastole to end-systole
  double filling_fraction = 0.25;         // rapid filling after end-systole, then still
  double longitudinal_shortening = 0.12;  // base toward apex, of the apex-to-point height
  // LV cavity radius at end-systole / end-diastole; the 5 mm grid blurs the kink at the endocardium,
  // so the sampled sequence ejects ~60 % where the analytic field would eject ~66 %
  double lv_radial_scale_es = 0.62;
  double twist_deg = 5.0;  // base and apex turn this much, opposite ways
};

// 0 at end-diastole, 1 at end-systole; C1 and periodic
double contraction(double phase, const SyntheticMotionSpec& spec);

// the displacement (m) of the tissue resting at rest_m (patient LPS) at contraction s in [0, 1]
Eigen::Vector3d synthetic_displacement_m(const Eigen::Vector3d& rest_m, double s, const SyntheticMotionSpec& spec);

// a grid of spacing_m covering the template heart's mesh with one spacing to spare on each side
// (the grid the built-in sequence, and motion recovered from images, are sampled on)
MotionGrid template_motion_grid(double spacing_m);

// sampled on template_motion_grid(spec.grid_spacing_m)
HeartMotion make_synthetic_heart_motion(const SyntheticMotionSpec& spec = {});

}  // namespace pcisim::anatomy
