// Motion from one 4-D NRRD (issue #14: "Frames as NRRD/MetaImage (a 4-D NRRD too)"): a small
// synthetic cine written as frame files and as one 4-D NRRD gives the same frames, and so the same
// recovered motion, bit for bit, as `pcisim-model motion --frames`/`--sequence DIR` and
// `--sequence FILE.nrrd` read them. Coarse (4 mm voxels, few demons iterations): the sameness is
// the point, not the accuracy (heart_motion_recovery_test.cc).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "anatomy/heart/synthetic_heart_motion.h"
#include "anatomy/volume/volume_io.h"
#include "modeling/motion/demons_motion.h"
#include "modeling/motion/synthetic_cine.h"

namespace pcisim::modeling {
namespace {

namespace fs = std::filesystem;

TEST(MotionFromNrrdSequence, AFourDNrrdGivesTheSameMotionAsItsFramesAsFiles) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("pcisim-motion-4d-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const anatomy::HeartMotion truth = anatomy::make_synthetic_heart_motion();
  CineSpec spec;
  spec.frames = 3;
  spec.voxel_mm = Eigen::Vector3d::Constant(4.0);
  spec.supersample = 1;
  spec.noise_sigma = 0.02;
  const CineSequence cine = render_synthetic_cine(truth, spec);

  // the folder, read as the motion subcommand reads --sequence DIR
  write_cine(cine, (dir / "frames").string());
  std::vector<std::string> paths;
  for (const auto& e : fs::directory_iterator(dir / "frames")) paths.push_back(e.path().string());
  std::vector<anatomy::Volume> from_files;
  for (const std::string& p : order_frame_files(paths)) from_files.push_back(anatomy::read_volume(p, true));
  // the 4-D file, read as --sequence FILE.nrrd reads it
  const std::string nrrd4d = (dir / "cine.nrrd").string();
  anatomy::write_nrrd_sequence(cine.frames, nrrd4d);
  const std::vector<anatomy::Volume> from_4d = anatomy::read_nrrd_sequence(nrrd4d, true);

  ASSERT_EQ(from_4d.size(), from_files.size());
  for (size_t f = 0; f < from_4d.size(); ++f) {
    EXPECT_EQ(from_4d[f].dims, from_files[f].dims) << f;
    EXPECT_EQ(from_4d[f].spacing_mm, from_files[f].spacing_mm) << f;
    EXPECT_EQ(from_4d[f].origin_mm, from_files[f].origin_mm) << f;
    EXPECT_EQ(from_4d[f].direction, from_files[f].direction) << f;
    EXPECT_EQ(from_4d[f].hu_f32, from_files[f].hu_f32) << f;
  }

  DemonsOptions o;
  o.levels = 2;
  o.iterations = 10;
  const anatomy::MotionGrid grid = anatomy::template_motion_grid(5e-3);
  const auto t0 = std::chrono::steady_clock::now();
  const anatomy::HeartMotion a = recover_heart_motion(from_files, truth.cycle_s(), grid, {}, o);
  const anatomy::HeartMotion b = recover_heart_motion(from_4d, truth.cycle_s(), grid, {}, o);
  std::printf("%zu frames of %lld x %lld x %lld voxels, recovered twice in %.2f s\n", from_4d.size(),
              (long long)from_4d[0].dims[0], (long long)from_4d[0].dims[1], (long long)from_4d[0].dims[2],
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  EXPECT_EQ(a.frames(), 3);
  EXPECT_EQ(a.serialize(), b.serialize());  // bit for bit
  // not vacuous: frame 1 moved
  double moved = 0.0;
  for (int k = 0; k < grid.dims.z(); ++k)
    for (int j = 0; j < grid.dims.y(); ++j)
      for (int i = 0; i < grid.dims.x(); ++i) moved = std::max(moved, a.node_displacement_m(1, i, j, k).norm());
  EXPECT_GT(moved, 1e-3);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pcisim::modeling
