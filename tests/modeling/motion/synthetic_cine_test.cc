// Synthetic cine sequences (issue #14): the template heart moved by the built-in synthetic motion,
// rendered on small grids (2.5 mm and coarser) so the whole file runs in seconds.
#include "modeling/motion/synthetic_cine.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <unistd.h>

#include "anatomy/heart/heart_frame.h"
#include "anatomy/heart/synthetic_heart_motion.h"
#include "anatomy/heart/template_heart_surface.h"
#include "anatomy/volume/volume_io.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

const anatomy::HeartMotion& truth() {
  static const anatomy::HeartMotion motion = anatomy::make_synthetic_heart_motion();
  return motion;
}

CineSpec small_spec() {
  CineSpec s;
  s.frames = 4;
  s.voxel_mm = Vector3d::Constant(2.5);
  s.supersample = 1;
  s.noise_sigma = 0.0;
  return s;
}

// heart frame (mm) -> patient LPS (m); the template's centre is the patient origin
Vector3d to_patient_m(const Vector3d& h_mm) {
  return anatomy::heart_to_patient() * h_mm * 1e-3;
}

// the LV cavity's radial axis (x' of the ellipsoid) in the heart frame
Vector3d lv_radial_axis() {
  const anatomy::CavityEllipsoid lv = anatomy::lv_cavity();
  return Eigen::AngleAxisd(lv.azimuth_rad, Vector3d::UnitZ()) * Vector3d::UnitX();
}

// along the LV's radial axis from its centre: the distance (mm) to the epicardium (bisection)
double lv_ray_to_epicardium_mm() {
  const anatomy::CavityEllipsoid lv = anatomy::lv_cavity();
  const Vector3d u = lv_radial_axis();
  double a = lv.semi_axes_mm.x(), b = 200.0;
  for (int it = 0; it < 60; ++it) {
    const double t = 0.5 * (a + b);
    const Vector3d p = lv.centre_mm + t * u;
    (p.norm() < anatomy::epicardial_radius_mm(p.normalized()) ? a : b) = t;
  }
  return 0.5 * (a + b);
}

// the test points (heart frame, mm)
struct Points {
  Vector3d blood, myocardium, fat, other;
};
Points test_points() {
  const anatomy::CavityEllipsoid lv = anatomy::lv_cavity();
  const Vector3d u = lv_radial_axis();
  const double endo = lv.semi_axes_mm.x(), epi = lv_ray_to_epicardium_mm();
  const Vector3d on_epi = lv.centre_mm + epi * u;
  const Vector3d radial = on_epi.normalized();
  return {lv.centre_mm, lv.centre_mm + 0.5 * (endo + epi) * u, on_epi + 1.0 * radial, on_epi + 30.0 * radial};
}

Vector3d voxel_centre_mm(const anatomy::Volume& v, int64_t i, int64_t j, int64_t k) {
  return v.index_to_physical_mm(Vector3d(double(i), double(j), double(k)));
}

float at_point(const anatomy::Volume& v, const Vector3d& p_mm) {
  const Vector3d ijk = v.physical_to_index(p_mm);
  return v.hu(std::lround(ijk.x()), std::lround(ijk.y()), std::lround(ijk.z()));
}

TEST(SyntheticCine, TemplateTissueClassesAtKnownPoints) {
  const Points p = test_points();
  const double wall_mm = lv_ray_to_epicardium_mm() - anatomy::lv_cavity().semi_axes_mm.x();
  std::printf("LV free wall along the cavity's radial axis: %.1f mm\n", wall_mm);
  ASSERT_GT(wall_mm, 5.0);
  EXPECT_EQ(template_tissue(to_patient_m(p.blood), 3.0), CineTissue::kBlood);
  EXPECT_EQ(template_tissue(to_patient_m(p.myocardium), 3.0), CineTissue::kMyocardium);
  EXPECT_EQ(template_tissue(to_patient_m(p.fat), 3.0), CineTissue::kFat);
  EXPECT_EQ(template_tissue(to_patient_m(p.other), 3.0), CineTissue::kOther);
  // the fat layer's width decides: 1 mm out is other without fat
  EXPECT_EQ(template_tissue(to_patient_m(p.fat), 0.5), CineTissue::kOther);
  // the RV cavity is blood too
  EXPECT_EQ(template_tissue(to_patient_m(anatomy::rv_cavity().centre_mm), 3.0), CineTissue::kBlood);
  EXPECT_EQ(cine_intensity(CineTissue::kBlood), 1.0f);
  EXPECT_EQ(cine_intensity(CineTissue::kMyocardium), 0.25f);
  EXPECT_EQ(cine_intensity(CineTissue::kFat), 0.85f);
  EXPECT_EQ(cine_intensity(CineTissue::kOther), 0.4f);
}

TEST(SyntheticCine, FrameZeroIsTheTemplateAtRest) {
  // the synthetic truth is end-diastole at phase 0: no displacement
  EXPECT_LT(truth().displacement_m(to_patient_m(test_points().myocardium), 0.0).norm(), 1e-12);
  const CineSequence seq = render_synthetic_cine(truth(), small_spec());
  ASSERT_EQ(seq.frames.size(), 4u);
  EXPECT_DOUBLE_EQ(seq.cycle_s, truth().cycle_s());
  const anatomy::Volume& v = seq.frames[0];
  EXPECT_EQ(v.type, anatomy::VoxelType::kFloat32);
  EXPECT_EQ(anatomy::validate(v), "");
  EXPECT_TRUE(v.direction.isIdentity());
  EXPECT_EQ(v.spacing_mm, Vector3d::Constant(2.5));
  // the grid covers the template plus the margin
  const anatomy::HeartSurface surface = anatomy::template_heart_surface();
  const Vector3d first = voxel_centre_mm(v, 0, 0, 0),
                 last = voxel_centre_mm(v, v.dims[0] - 1, v.dims[1] - 1, v.dims[2] - 1);
  for (const Vector3d& q : surface.vertices_mm) {
    EXPECT_TRUE(((q - first).array() >= 12.0 - 1e-9).all() && ((last - q).array() >= 12.0 - 1e-9).all());
  }
  // the four points: their voxel has their class's intensity (no noise, one sample per voxel);
  // fat (3 mm thick) is checked below through every voxel
  const Points p = test_points();
  EXPECT_EQ(at_point(v, anatomy::heart_to_patient() * p.blood), cine_intensity(CineTissue::kBlood));
  EXPECT_EQ(at_point(v, anatomy::heart_to_patient() * p.myocardium), cine_intensity(CineTissue::kMyocardium));
  EXPECT_EQ(at_point(v, anatomy::heart_to_patient() * p.other), cine_intensity(CineTissue::kOther));
  // every voxel of frame 0 is the rest class of its centre
  int64_t mismatches = 0, counts[4] = {0, 0, 0, 0};
  for (int64_t k = 0; k < v.dims[2]; ++k)
    for (int64_t j = 0; j < v.dims[1]; ++j)
      for (int64_t i = 0; i < v.dims[0]; ++i) {
        const CineTissue t = template_tissue(voxel_centre_mm(v, i, j, k) * 1e-3, 3.0);
        ++counts[int(t)];
        mismatches += v.hu(i, j, k) != cine_intensity(t);
      }
  std::printf("frame 0: %ld x %ld x %ld voxels; blood %ld, myocardium %ld, fat %ld, other %ld\n", long(v.dims[0]),
              long(v.dims[1]), long(v.dims[2]), long(counts[0]), long(counts[1]), long(counts[2]), long(counts[3]));
  EXPECT_EQ(mismatches, 0);
  for (int64_t c : counts) EXPECT_GT(c, 100);
  // later frames move: the heart is not the rest classes there
  int64_t moved = 0;
  for (int64_t n = 0; n < v.voxel_count(); ++n) moved += seq.frames[1].hu_f32[n] != v.hu_f32[n];
  EXPECT_GT(moved, 1000);
}

TEST(SyntheticCine, RestPointsInvertTheMotionAtEndSystole) {
  anatomy::SyntheticMotionSpec motion_spec;
  const double es_phase = motion_spec.systole_fraction;
  ASSERT_DOUBLE_EQ(es_phase, 0.35);
  CineSpec s = small_spec();
  s.frames = 2;
  s.voxel_mm = Vector3d::Constant(5.0);  // only the grid's geometry is used
  const anatomy::Volume v = render_synthetic_cine(truth(), s).frames[0];
  std::mt19937_64 rng(7);
  int tried = 0, near_heart = 0;
  double worst_m = 0.0, largest_move_m = 0.0;
  while (tried < 400) {
    // voxel centres of a 1.5 mm grid over the same box, most near the heart
    const Vector3d x_mm = v.origin_mm + Vector3d(std::uniform_real_distribution<double>(0, 1)(rng),
                                                 std::uniform_real_distribution<double>(0, 1)(rng),
                                                 std::uniform_real_distribution<double>(0, 1)(rng))
                                            .cwiseProduct(Vector3d(v.dims[0] - 1, v.dims[1] - 1, v.dims[2] - 1) * 5.0);
    const Vector3d snapped = (x_mm / 1.5).array().round() * 1.5;
    if (snapped.norm() > 70.0 && tried % 4 != 0) continue;
    ++tried;
    near_heart += snapped.norm() <= 70.0;
    const Vector3d x_m = snapped * 1e-3;
    const Vector3d r = cine_rest_point_m(truth(), x_m, es_phase);
    worst_m = std::max(worst_m, (r + truth().displacement_m(r, es_phase) - x_m).norm());
    largest_move_m = std::max(largest_move_m, (r - x_m).norm());
  }
  std::printf(
      "end-systole inversion, %d points (%d near the heart): worst |r + d(r) - x| %.2e m, largest move %.1f mm\n",
      tried, near_heart, worst_m, largest_move_m * 1e3);
  EXPECT_LT(worst_m, 1e-6);
  EXPECT_GT(largest_move_m, 3e-3);  // the points did move: the test is not of a still heart
}

TEST(SyntheticCine, BloodInTheLvFollowsTheTruthsEjection) {
  // phase 7/20 = 0.35 is end-systole; 2.5 mm voxels, 2 x 2 x 2 samples, blood above the midpoint
  // between blood and myocardium
  CineSpec s = small_spec();
  s.frames = 20;
  s.supersample = 2;
  anatomy::SyntheticMotionSpec motion_spec;
  const int es = static_cast<int>(std::lround(motion_spec.systole_fraction * s.frames));
  ASSERT_DOUBLE_EQ(double(es) / s.frames, motion_spec.systole_fraction);
  // the two frames alone (render_synthetic_cine's frames are these, tested below)
  const anatomy::Volume ed_frame = render_synthetic_cine_frame(truth(), s, 0);
  const anatomy::Volume es_frame = render_synthetic_cine_frame(truth(), s, es);
  const anatomy::CavityEllipsoid lv = anatomy::lv_cavity(), rv = anatomy::rv_cavity();
  auto inside = [](const anatomy::CavityEllipsoid& c, const Vector3d& h_mm, double grow) {
    const Vector3d q = Eigen::AngleAxisd(c.azimuth_rad, Vector3d::UnitZ()).inverse() * (h_mm - c.centre_mm);
    return q.cwiseQuotient(grow * c.semi_axes_mm).squaredNorm() <= 1.0;
  };
  const float threshold = 0.5f * (cine_intensity(CineTissue::kBlood) + cine_intensity(CineTissue::kMyocardium));
  auto lv_blood = [&](const anatomy::Volume& v, int64_t* rv_in_region) {
    int64_t n = 0;
    for (int64_t k = 0; k < v.dims[2]; ++k)
      for (int64_t j = 0; j < v.dims[1]; ++j)
        for (int64_t i = 0; i < v.dims[0]; ++i) {
          const Vector3d h_mm = anatomy::heart_to_patient().transpose() * voxel_centre_mm(v, i, j, k);
          // the region: the LV cavity grown by 15 % (the RV stays ~10 mm beyond it)
          if (!inside(lv, h_mm, 1.15)) continue;
          if (rv_in_region) *rv_in_region += inside(rv, h_mm, 1.0);
          n += v.hu(i, j, k) > threshold;
        }
    return n;
  };
  int64_t rv_in_region = 0;
  const int64_t ed = lv_blood(ed_frame, &rv_in_region), esn = lv_blood(es_frame, nullptr);
  const double voxel_ml = 2.5 * 2.5 * 2.5 * 1e-3;
  const double ratio = double(esn) / double(ed), truth_ratio = 31.5 / 79.3;
  std::printf(
      "LV blood: end-diastole %.1f ml, end-systole %.1f ml, ES/ED %.3f (truth 31.5 / 79.3 = %.3f), EF %.1f %%\n",
      ed * voxel_ml, esn * voxel_ml, ratio, truth_ratio, 100.0 * (1.0 - ratio));
  EXPECT_EQ(rv_in_region, 0);
  // the ellipsoid's own volume, 4/3 pi 24 24 34 = 82.0 ml (the truth's mesh cavity, 162 vertices,
  // holds 79.3): 2.5 mm voxels over its ~9300 mm^2 wall count it within a few per cent
  EXPECT_NEAR(ed * voxel_ml, 82.0, 2.5);
  // the truth's ratio is of the polyhedral mesh cavity; the images see the smooth ellipsoid moved
  // by the same sampled field (~3 % apart at end-diastole) and count whole voxels (~1-2 % of the
  // 31 ml end-systolic cavity at 2.5 mm): +-0.03 on the ratio (~8 %)
  EXPECT_NEAR(ratio, truth_ratio, 0.03);
}

TEST(SyntheticCine, NoiseHasItsSigmaAndFollowsTheSeed) {
  CineSpec s = small_spec();
  s.frames = 2;
  s.voxel_mm = Vector3d::Constant(4.0);
  const CineSequence clean = render_synthetic_cine(truth(), s);
  s.noise_sigma = 0.05;
  const CineSequence noisy = render_synthetic_cine(truth(), s);
  const CineSequence again = render_synthetic_cine(truth(), s);
  CineSpec other_seed = s;
  other_seed.seed = 2;
  const CineSequence reseeded = render_synthetic_cine(truth(), other_seed);
  for (int f = 0; f < 2; ++f) {
    double sum = 0, sum2 = 0;
    int64_t n = 0;
    for (int64_t i = 0; i < clean.frames[f].voxel_count(); ++i) {
      if (clean.frames[f].hu_f32[i] != cine_intensity(CineTissue::kOther)) continue;
      const double v = noisy.frames[f].hu_f32[i];
      sum += v;
      sum2 += v * v;
      ++n;
    }
    const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
    std::printf("frame %d: 'other' region of %ld voxels, mean %.4f, sd %.4f\n", f, long(n), mean, sd);
    ASSERT_GT(n, 5000);
    EXPECT_NEAR(sd, 0.05, 0.005);
    EXPECT_NEAR(mean, 0.4, 0.005);
    EXPECT_EQ(std::memcmp(noisy.frames[f].data(), again.frames[f].data(), noisy.frames[f].data_bytes()), 0);
    EXPECT_NE(std::memcmp(noisy.frames[f].data(), reseeded.frames[f].data(), noisy.frames[f].data_bytes()), 0);
  }
  // a frame renders alone, bit-identical; one out of range is refused
  const anatomy::Volume alone = render_synthetic_cine_frame(truth(), s, 1);
  EXPECT_EQ(std::memcmp(alone.data(), noisy.frames[1].data(), alone.data_bytes()), 0);
  EXPECT_THROW(render_synthetic_cine_frame(truth(), s, 2), std::invalid_argument);
  EXPECT_THROW(render_synthetic_cine_frame(truth(), s, -1), std::invalid_argument);
  // the two frames draw different noise
  int64_t same = 0;
  for (int64_t i = 0; i < clean.frames[0].voxel_count(); ++i)
    same += (noisy.frames[0].hu_f32[i] - clean.frames[0].hu_f32[i]) ==
            (noisy.frames[1].hu_f32[i] - clean.frames[1].hu_f32[i]);
  EXPECT_LT(same, clean.frames[0].voxel_count() / 100);
}

TEST(SyntheticCine, PartialVolumeAndThickSlicesBlendTheClasses) {
  // one sample per voxel gives only the four intensities; supersampling blends at boundaries, and
  // a thick slice blends more (along z) while keeping the volume's mean intensity
  CineSpec s = small_spec();
  s.frames = 2;
  s.voxel_mm = Vector3d::Constant(5.0);
  auto mixed = [](const anatomy::Volume& v, double* mean) {
    int64_t n = 0;
    double sum = 0;
    for (float x : v.hu_f32) {
      sum += x;
      n += x != 1.0f && x != 0.25f && x != 0.85f && x != 0.4f;
    }
    *mean = sum / v.voxel_count();
    return n;
  };
  double m1, m2, m3;
  const int64_t point = mixed(render_synthetic_cine(truth(), s).frames[0], &m1);
  s.supersample = 2;
  const int64_t pv = mixed(render_synthetic_cine(truth(), s).frames[0], &m2);
  s.slice_thickness_mm = 10.0;
  const int64_t thick = mixed(render_synthetic_cine(truth(), s).frames[0], &m3);
  std::printf("blended voxels: 1 sample %ld, 2^3 samples %ld, 10 mm slices %ld; mean %.4f %.4f %.4f\n", long(point),
              long(pv), long(thick), m1, m2, m3);
  EXPECT_EQ(point, 0);
  EXPECT_GT(pv, 500);
  EXPECT_GT(thick, pv * 1.3);
  EXPECT_NEAR(m2, m1, 0.01);
  EXPECT_NEAR(m3, m2, 0.01);
}

TEST(SyntheticCine, ValidateNamesTheBadFieldAndRenderRefusesIt) {
  EXPECT_EQ(validate(CineSpec{}), "");
  auto message = [](auto change) {
    CineSpec s;
    change(s);
    return validate(s);
  };
  EXPECT_EQ(message([](CineSpec& s) { s.frames = 1; }), "frames: must be 2..200, got 1");
  EXPECT_EQ(message([](CineSpec& s) { s.frames = 201; }).rfind("frames:", 0), 0u);
  EXPECT_EQ(message([](CineSpec& s) { s.voxel_mm.x() = 0; }).rfind("voxel_mm.x:", 0), 0u);
  EXPECT_EQ(message([](CineSpec& s) { s.voxel_mm.y() = -1; }).rfind("voxel_mm.y:", 0), 0u);
  EXPECT_EQ(message([](CineSpec& s) { s.voxel_mm.z() = NAN; }).rfind("voxel_mm.z:", 0), 0u);
  EXPECT_EQ(message([](CineSpec& s) { s.slice_thickness_mm = -1; }).rfind("slice_thickness_mm:", 0), 0u);
  EXPECT_EQ(message([](CineSpec& s) { s.margin_mm = -2; }).rfind("margin_mm:", 0), 0u);
  EXPECT_EQ(message([](CineSpec& s) { s.fat_mm = INFINITY; }).rfind("fat_mm:", 0), 0u);
  EXPECT_EQ(message([](CineSpec& s) { s.noise_sigma = -0.1; }).rfind("noise_sigma:", 0), 0u);
  EXPECT_EQ(message([](CineSpec& s) { s.supersample = 0; }).rfind("supersample:", 0), 0u);
  CineSpec bad = small_spec();
  bad.supersample = 9;
  try {
    render_synthetic_cine(truth(), bad);
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("supersample:", 0), 0u) << e.what();
  }
}

TEST(SyntheticCine, WrittenFramesReadBackBitIdentical) {
  CineSpec s = small_spec();
  s.frames = 3;
  s.voxel_mm = Vector3d(5.0, 4.0, 6.0);
  s.noise_sigma = 0.03;
  const CineSequence seq = render_synthetic_cine(truth(), s);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("pcisim_cine_test_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  write_cine(seq, (dir / "sub").string());
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir / "sub")) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 3);
  for (int f = 0; f < 3; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%03d.nrrd", f);
    const anatomy::Volume back = anatomy::read_volume((dir / "sub" / name).string(), true);
    const anatomy::Volume& v = seq.frames[f];
    EXPECT_EQ(back.type, anatomy::VoxelType::kFloat32);
    EXPECT_EQ(back.dims, v.dims);
    EXPECT_EQ(back.spacing_mm, v.spacing_mm);
    EXPECT_EQ(back.origin_mm, v.origin_mm);
    EXPECT_EQ(back.direction, v.direction);
    ASSERT_EQ(back.data_bytes(), v.data_bytes());
    EXPECT_EQ(std::memcmp(back.data(), v.data(), v.data_bytes()), 0) << name;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pcisim::modeling
