// The x-ray thread's frame path (server/xray_loop.h): once warm, rendering and publishing a frame
// allocates nothing (issue #36 item 5: lcm-cpp's publish allocated a buffer per frame, and the
// frame's branch names were copied into a new vector each time).
#include "server/xray_loop.h"

#include <gtest/gtest.h>

#include "realtime/allocation_count.h"
#include "server/case_builder.h"
#include "server/scene/scene.h"

namespace pcisim::server {
namespace {

TEST(XrayLoop, FramesAllocateNothingOnceWarm) {
  const Scene scene = parse_scene(R"({
    "name": "frames",
    "effects": {
      "guidewire": {"segments": 60},
      "xray": {"detector_px": 96, "pixel_mm": 2.0, "volume_voxels": 96, "volume_spacing_mm": 3.7},
      "contrast": {"injection_ml": 8, "injection_s": 2}
    }
  })",
                                  "frames");
  const auto anatomy = build_case(scene);
  SharedState state;
  lcm::LCM images("memq://");
  int frames_seen = 0;
  struct Counter {
    int* n;
    void on_frame(const lcm::ReceiveBuffer*, const std::string&) { ++*n; }
  } counter{&frames_seen};
  images.subscribe(protocol::kXrayChannel, &Counter::on_frame, &counter);
  XrayLoop loop(scene, *anatomy, state, &images);
  // a wire of 61 nodes down the first branch's first points, and a contrast injection under way
  physics::WorldSnapshot& snap = state.snapshot_for_xray.write_slot();
  const auto& points = anatomy->vessels.branches.front().points;
  for (int i = 0; i < 61; ++i) snap.wire_nodes_m.push_back(points[i % points.size()].position_m);
  snap.time_s = 0.5;
  state.snapshot_for_xray.publish();
  state.injection_start_s[0] = 0.2;
  state.injections.store(1);
  for (int k = 0; k < 3; ++k) loop.render_and_publish(false);  // warm: sizes, the injection's buffers
  long allocations = -1;
  {
    realtime::AllocationCount count;
    for (int k = 0; k < 10; ++k) loop.render_and_publish(false);
    allocations = count.allocations();
  }
  while (images.handleTimeout(0) > 0) {}
  EXPECT_EQ(frames_seen, 13) << "every frame was published";
  EXPECT_EQ(allocations, 0) << "a frame allocated";
}

}  // namespace
}  // namespace pcisim::server
