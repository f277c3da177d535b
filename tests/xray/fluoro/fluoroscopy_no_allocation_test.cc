// Proves a fluoroscopy frame allocates nothing once the frame size is known
// (realtime/allocation_count.h counts this thread's allocations).
#include <gtest/gtest.h>

#include <cmath>

#include "realtime/allocation_count.h"
#include "tests/xray/fluoro/fluoro_test_util.h"

namespace pcisim::xray {
namespace {

TEST(FluoroscopyNoAllocation, SecondAndLaterFramesAllocateNothing) {
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({.seed = 1});
  FluoroSpec s = testing::small_fluoro_spec();  // CPU projector, noise and blur on
  FluoroscopyRenderer fr(tree, s);
  const auto& lad = tree.branches[tree.find("LAD")].points;
  std::vector<Eigen::Vector3d> wire_m;
  for (size_t i = 0; i < 120; ++i) wire_m.push_back(lad[i].position_m);
  const ContrastInjection inj[2] = {
      {.start_s = 0, .duration_s = 2, .volume_ml = 8},
      {.start_s = 0.5, .duration_s = 1, .volume_ml = 4, .ostium = CoronaryOstium::kRight}};
  FluoroFrame f;
  fr.render({.time_s = 0, .pose = testing::lao30_cra20(), .wire_m = wire_m, .injections = inj}, f);
  long allocations = -1;
  {
    pcisim::realtime::AllocationCount count;
    for (int i = 1; i <= 6; ++i) {  // the bolus spreads, more branches become visible, the wire moves
      for (auto& p : wire_m) p.x() += 1e-4;
      fr.render({.time_s = 0.3 * i, .pose = testing::lao30_cra20(), .wire_m = wire_m, .injections = inj}, f);
    }
    allocations = count.allocations();
  }
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(fr.background_renders(), 1);
  EXPECT_FALSE(f.contrast_branches.empty());
}

// with the background beating: once the pose has every bin, frames at any phase allocate nothing
TEST(FluoroscopyNoAllocation, BeatingFramesAllocateNothingOnceThePoseHasEveryBin) {
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({.seed = 1});
  FluoroSpec s = testing::small_fluoro_spec();
  FluoroscopyRenderer fr(tree, s);
  // a cycle of 8 bins: the points within 40 mm of the heart centre swing by up to 5 mm
  BeatSamples beat;
  for (double x = -40; x <= 40; x += 8)
    for (double y = -40; y <= 40; y += 8)
      for (double z = -40; z <= 40; z += 8)
        if (Eigen::Vector3d(x, y, z).norm() <= 40) beat.rest_mm.emplace_back(x, y, z);
  for (int b = 0; b < 8; ++b) {
    beat.at_bin_mm.emplace_back();
    for (const auto& p : beat.rest_mm)
      beat.at_bin_mm.back().push_back(p + Eigen::Vector3d(5 * std::sin(b * 0.785), 0, 2 * std::cos(b * 0.785)));
  }
  fr.set_beat(beat, {.projector = {.step_voxels = 1.0, .threads = 1}});
  FluoroFrame f;
  FluoroInput in{.time_s = 0, .pose = testing::lao30_cra20()};
  in.heart_phase = 0.1;
  fr.render(in, f);
  while (fr.work_ahead() > 0) {}
  ASSERT_EQ(fr.beat()->filled_bins(), 8);
  long allocations = -1;
  {
    pcisim::realtime::AllocationCount count;
    for (int i = 1; i <= 6; ++i) {
      in.time_s = 0.1 * i;
      in.heart_phase = 0.17 * i;
      fr.render(in, f);
    }
    allocations = count.allocations();
  }
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(fr.beat()->bin_projections(), 8);  // each bin projected once for the pose
}

}  // namespace
}  // namespace pcisim::xray
