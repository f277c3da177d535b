// Proves a fluoroscopy frame allocates nothing once the frame size is known
// (tests/common/counting_new.h counts this thread's allocations).
#include <gtest/gtest.h>

#include "tests/common/counting_new.h"
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
    pcisim::testing::AllocationCount count;
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

}  // namespace
}  // namespace pcisim::xray
