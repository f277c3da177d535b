// Motion from images against exact truth: the built-in synthetic contraction rendered as a cine
// sequence (synthetic_cine.h), end-diastole registered to end-systole by demons, and the recovered
// displacement compared with the truth at every ventricular point of the template heart (the
// points the beating heart drives). Also: the recovered motion survives the motion file's round trip
// (the main job driven by such a file: docs/heart.md, by hand).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "anatomy/heart/heart_frame.h"
#include "anatomy/heart/heart_mesh.h"
#include "anatomy/heart/synthetic_heart_motion.h"
#include "modeling/motion/demons_motion.h"
#include "modeling/motion/synthetic_cine.h"
#include "realtime/percentile.h"

namespace pcisim::modeling {
namespace {

TEST(HeartMotionRecovery, EndSystoleFromACineSequenceAtTheVentricularPoints) {
  const anatomy::HeartMotion truth = anatomy::make_synthetic_heart_motion();
  CineSpec cine;
  cine.voxel_mm = Eigen::Vector3d::Constant(2.5);
  cine.noise_sigma = 0.03;
  const int es = 7;  // phase 0.35 of 20 frames: end-systole, the largest motion
  const std::vector<anatomy::Volume> frames = {render_synthetic_cine_frame(truth, cine, 0),
                                               render_synthetic_cine_frame(truth, cine, es)};
  DemonsOptions o;
  o.levels = 3;
  o.iterations = 50;
  o.field_sigma_vox = 1.5;
  std::vector<MotionFrameReport> reports;
  const anatomy::HeartMotion got =
      recover_heart_motion(frames, truth.cycle_s(), anatomy::template_motion_grid(2.5e-3), {}, o, &reports);

  const Eigen::Matrix3Xd& rest = anatomy::template_heart_mesh().vertices_m;
  const std::vector<int> ventricles = anatomy::ventricular_points(rest);
  ASSERT_GT(ventricles.size(), 100u);
  std::vector<double> err_mm;
  double moved_mm = 0.0, moved_mean_mm = 0.0;
  for (int i : ventricles) {
    const Eigen::Vector3d want = truth.displacement_m(rest.col(i), double(es) / truth.frames());
    const Eigen::Vector3d have = got.frame_displacement_m(1, rest.col(i));
    err_mm.push_back(1e3 * (have - want).norm());
    moved_mm = std::max(moved_mm, 1e3 * want.norm());
    moved_mean_mm += 1e3 * want.norm() / ventricles.size();
  }
  double mean = 0.0;
  for (double e : err_mm) mean += e / err_mm.size();
  const double p95 = realtime::percentile(err_mm, 0.95);
  const double worst = *std::max_element(err_mm.begin(), err_mm.end());
  std::printf(
      "end-systole, %zu ventricular points, truth mean %.1f / up to %.1f mm: error mean %.2f, p95 %.2f, worst "
      "%.2f mm; residual %.4f -> %.4f; demons %.1f s\n",
      ventricles.size(), moved_mean_mm, moved_mm, mean, p95, worst, reports[0].rms_before, reports[0].rms_after,
      reports[0].seconds);
  // this setting (3 levels x 50 iterations, sigma 1.5) measured 2.81 mm mean, 5.95 mm p95, 8.22 mm
  // worst against 6.5 mm of mean motion (docs/benchmarks/motion.md; the same here on every run).
  // Plain cine contrast leaves the motion along uniform tissue unseen (the aperture problem;
  // docs/heart.md, 'Motion from images'), so this is not issue #14's 0.5 mm target (missed). The
  // bounds sit 10-15 % above the measured figures, so that the benchmark's worse settings fail:
  // 2 levels x 20 iterations at sigma 1.0 (4.16 / 7.50 / 10.00 mm), 2 x 20 at 1.5 (3.71 / 6.83),
  // 2 x 50 at 1.0 (3.54 / 6.90) and 2 x 50 at 1.5 (3.22 mean), as does a field a fifth too short
  // (3.23 mean). No field at all is off by the whole motion.
  EXPECT_GT(moved_mm, 8.0);
  EXPECT_LT(mean, 3.1);
  EXPECT_LT(p95, 6.6);
  EXPECT_LT(worst, 9.5);
  // residual RMS 0.1587 -> 0.0483 measured (0.30 of it; every benchmarked setting ends at 0.28 to
  // 0.42 of it): the images were matched
  EXPECT_LT(reports[0].rms_after, 0.45 * reports[0].rms_before);

  // the file round trip: what the beating heart would read back, every sample of every frame
  const auto path = std::filesystem::temp_directory_path() / "pcisim_recovered.motion";
  got.write(path.string());
  const anatomy::HeartMotion back = anatomy::HeartMotion::read(path.string());
  std::filesystem::remove(path);
  ASSERT_EQ(back.frames(), 2);
  EXPECT_EQ(back.cycle_s(), got.cycle_s());
  EXPECT_EQ(back.grid().origin_m, got.grid().origin_m);
  EXPECT_EQ(back.grid().spacing_m, got.grid().spacing_m);
  ASSERT_EQ(back.grid().dims, got.grid().dims);
  const Eigen::Vector3i dims = got.grid().dims;
  long differ = 0, moving = 0;
  for (int f = 0; f < got.frames(); ++f)
    for (int k = 0; k < dims.z(); ++k)
      for (int j = 0; j < dims.y(); ++j)
        for (int i = 0; i < dims.x(); ++i) {
          const Eigen::Vector3d want = got.node_displacement_m(f, i, j, k);
          differ += back.node_displacement_m(f, i, j, k) != want;
          moving += want != Eigen::Vector3d::Zero();
        }
  EXPECT_EQ(differ, 0) << "of " << 2 * got.grid().node_count() << " nodes";
  EXPECT_GT(moving, got.grid().node_count() / 10);  // frame 1 holds a field, not zeros
  // and what the heart samples: every ventricular point at both frames
  for (int f = 0; f < 2; ++f)
    for (int i : ventricles)
      ASSERT_EQ(back.frame_displacement_m(f, rest.col(i)), got.frame_displacement_m(f, rest.col(i)))
          << "frame " << f << ", point " << i;
}

}  // namespace
}  // namespace pcisim::modeling
