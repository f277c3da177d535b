// Proves a fluoroscopy frame allocates nothing once the frame size is known: global operator new
// is replaced in this test binary and counts the allocations made by the calling thread.
#include <gtest/gtest.h>

#include <cstdlib>
#include <new>

#include "tests/xray/fluoro/fluoro_test_util.h"

namespace {
thread_local bool g_counting = false;
thread_local long g_allocations = 0;
}  // namespace

void* operator new(std::size_t n) {
  if (g_counting) ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace pcisim::xray {
namespace {

TEST(FluoroscopyNoAllocation, CounterSeesAnAllocation) {
  g_allocations = 0;
  g_counting = true;
  void* p = ::operator new(16);
  g_counting = false;
  ::operator delete(p);
  EXPECT_EQ(g_allocations, 1);
}

TEST(FluoroscopyNoAllocation, SecondAndLaterFramesAllocateNothing) {
  const physics::VesselTree tree = physics::make_coronary_phantom({.seed = 1});
  FluoroSpec s = testing::small_fluoro_spec();  // CPU projector, noise and blur on
  FluoroscopyRenderer fr(tree, s);
  const auto& lad = tree.branches[tree.find("LAD")].points;
  std::vector<Eigen::Vector3d> wire_m;
  for (size_t i = 0; i < 120; ++i) wire_m.push_back(lad[i].position_m);
  const ContrastInjection inj[2] = {{.start_s = 0, .duration_s = 2, .volume_ml = 8},
                                    {.start_s = 0.5, .duration_s = 1, .volume_ml = 4, .ostium = CoronaryOstium::kRight}};
  FluoroFrame f;
  fr.render({.time_s = 0, .pose = testing::lao30_cra20(), .wire_m = wire_m, .injections = inj}, f);
  g_allocations = 0;
  g_counting = true;
  for (int i = 1; i <= 6; ++i) {  // the bolus spreads, more branches become visible, the wire moves
    for (auto& p : wire_m) p.x() += 1e-4;
    fr.render({.time_s = 0.3 * i, .pose = testing::lao30_cra20(), .wire_m = wire_m, .injections = inj}, f);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations, 0);
  EXPECT_EQ(fr.background_renders(), 1);
  EXPECT_FALSE(f.contrast_branches.empty());
}

}  // namespace
}  // namespace pcisim::xray
