// One encode buffer kept between publishes (issue #36 item 5): an X-ray frame of half a megabyte
// and force commands published over and over allocate nothing once the buffer has grown to the
// largest, and arrive intact.
#include "protocol/encoded_publisher.h"

#include <gtest/gtest.h>

#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/allocation_count.h"

namespace pcisim::protocol {
namespace {

struct Received {
  int frames = 0, forces = 0;
  int64_t last_frame_seq = -1;
  uint8_t last_frame_byte = 0;
  double last_force_n = 0.0;
  void on_frame(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::xray_frame_t m;
    ASSERT_TRUE(decode_checked(*r, m));
    ++frames;
    last_frame_seq = m.seq;
    last_frame_byte = m.data.back();
  }
  void on_force(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::force_command_t m;
    ASSERT_TRUE(decode_checked(*r, m));
    ++forces;
    last_force_n = m.axial_force_n;
  }
};

TEST(EncodedPublisher, AFrameAndForcesAllocateNothingOnceTheBufferHasGrownAndArriveIntact) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  Received got;
  lcm.subscribe(kXrayChannel, &Received::on_frame, &got);
  lcm.subscribe(kForceChannel, &Received::on_force, &got);
  pcisim_lcm::xray_frame_t frame{};
  frame.width = frame.height = 512;
  frame.pixel_format = pcisim_lcm::xray_frame_t::FORMAT_GRAY16;
  frame.num_bytes = 512 * 512 * 2;
  frame.data.assign(static_cast<size_t>(frame.num_bytes), 7);
  pcisim_lcm::force_command_t force{};
  const std::string xray = kXrayChannel, force_channel = kForceChannel;
  EncodedPublisher publisher;
  ASSERT_EQ(publisher.publish(lcm, xray, frame), 0);  // the buffer grows to the frame
  EXPECT_EQ(publisher.grown(), 1);
  {
    pcisim::realtime::AllocationCount count;
    for (int k = 1; k <= 20; ++k) {
      frame.seq = k;
      frame.data.back() = static_cast<uint8_t>(k);
      ASSERT_EQ(publisher.publish(lcm, xray, frame), 0);
      force.axial_force_n = 0.01 * k;
      ASSERT_EQ(publisher.publish(lcm, force_channel, force), 0);  // smaller: the same buffer
    }
    EXPECT_EQ(count.allocations(), 0);
  }
  EXPECT_EQ(publisher.grown(), 1);
  while (lcm.handleTimeout(0) > 0) {}
  EXPECT_EQ(got.frames, 21);
  EXPECT_EQ(got.forces, 20);
  EXPECT_EQ(got.last_frame_seq, 20);
  EXPECT_EQ(got.last_frame_byte, 20);
  EXPECT_DOUBLE_EQ(got.last_force_n, 0.2);
}

}  // namespace
}  // namespace pcisim::protocol
