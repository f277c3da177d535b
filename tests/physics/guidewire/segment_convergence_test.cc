// Convergence in the segment count: the built-in trainee's session (turned toward the LAD or
// the LCx) gives the same answer with 200, 400 and 800 links. Finer wires stay inside the lumen after every step, end
// in the same branch at the same place, so a fine wire can serve as the benchmark's reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "anatomy/vessel/vessel_tree.h"
#include "tests/physics/guidewire/wire_test_support.h"
#include "tests/common/shared_lumen.h"

namespace pcisim::physics {
namespace {

struct Session {
  std::vector<Eigen::Vector3d> tips;  // tip after every step
  double worst_wall_m = -1.0;         // deepest any free node ended a step outside the lumen
  std::string final_branch;
  std::string final_main_branch;  // the LAD for its diagonals, the LCx for its marginals
  int bad_links_at_end = 0;
};

Session run_session(int segments, double turn_deg) {
  WorldSpec spec = test::default_scene();
  spec.guidewire->segment_count = segments;
  World world = test::make_world(spec);
  test::BranchScript script;
  script.turn_deg = turn_deg;
  Session s;
  for (double t = 0.0; t <= script.end_s(); t += spec.step_s) {
    world.step(script.at(t));
    const ChainMailWire& w = *world.guidewire_state();
    s.worst_wall_m = std::max(s.worst_wall_m, test::worst_wall_distance_m(w, *world.lumen()));
    s.tips.push_back(w.nodes_m().back());
  }
  WorldSnapshot snap;
  world.write_snapshot(snap);
  s.final_branch = snap.tip_branch >= 0 ? world.vessel_tree().branches[snap.tip_branch].name : "-";
  const auto& tree = world.vessel_tree();
  int b = snap.tip_branch;
  while (b >= 0 && tree.branches[b].name != "LAD" && tree.branches[b].name != "LCx") b = tree.branches[b].parent;
  s.final_main_branch = b >= 0 ? tree.branches[b].name : s.final_branch;
  s.bad_links_at_end = test::check_limits(*world.guidewire_state()).bad_links;
  return s;
}

void expect_converged(double turn_deg, const char* branch) {
  const Session coarse = run_session(200, turn_deg);
  const Session mid = run_session(400, turn_deg);
  const Session fine = run_session(800, turn_deg);
  ASSERT_EQ(coarse.final_branch, branch);
  for (const Session* s : {&mid, &fine}) {
    // within 0.1 mm of the lumen after every step (the wall margin is 0.05 mm inside)
    EXPECT_LE(s->worst_wall_m, 0.1e-3) << "turn " << turn_deg;
    // the same vessel; at 44-50 mm the tip reaches a side-branch ostium (D1, OM1) where a finer
    // wire may prolapse into the side branch (sensitive to the blood's pull, docs/heart.md)
    EXPECT_EQ(s->final_main_branch, coarse.final_main_branch) << "turn " << turn_deg << ": " << s->final_branch;
    EXPECT_EQ(s->bad_links_at_end, 0) << "turn " << turn_deg;
  }
  // 400 and 800 links end at the same place, and follow the same path on the whole (the finer
  // tip can be held up longer at an ostium, so single steps may differ by a centimetre)
  ASSERT_EQ(mid.tips.size(), fine.tips.size());
  double sum_sq = 0.0;
  for (size_t k = 0; k < mid.tips.size(); ++k) sum_sq += (mid.tips[k] - fine.tips[k]).squaredNorm();
  const double rms_m = std::sqrt(sum_sq / static_cast<double>(mid.tips.size()));
  EXPECT_LE(rms_m, 8e-3) << "turn " << turn_deg << ": tip RMS gap " << rms_m * 1e3 << " mm";
  // where both end in the same branch they end at the same place
  if (mid.final_branch == fine.final_branch) {
    EXPECT_LE((mid.tips.back() - fine.tips.back()).norm(), 2.5e-3) << "turn " << turn_deg;
  }
  if (coarse.final_branch == fine.final_branch) {
    EXPECT_LE((coarse.tips.back() - fine.tips.back()).norm(), 3e-3) << "turn " << turn_deg;
  }
}

TEST(SegmentConvergence, FinerWiresReachTheLadLikeTheDefaultWire) {
  expect_converged(90.0, "LAD");
}

TEST(SegmentConvergence, FinerWiresReachTheLcxLikeTheDefaultWire) {
  expect_converged(-90.0, "LCx");
}

}  // namespace
}  // namespace pcisim::physics
