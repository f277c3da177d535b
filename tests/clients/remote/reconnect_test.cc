// Pages come and go: a dropped connection frees everything it held (its slot, the pedal it held
// down, the keyboard instrument), and a page that comes back sees the last image at once.
#include <gtest/gtest.h>

#include "clients/remote/keyboard_instrument.h"
#include "remote_test_support.h"

namespace pcisim::remote::test {
namespace {

using C = pcisim_lcm::session_command_t;

TEST(RemoteReconnect, DroppedPageIsForgottenAndAReturningPageSeesTheLastImage) {
  TestGateway g;
  auto f = make_frame(41, 64);
  {
    WsClient first;
    ASSERT_EQ(first.connect(g.port(), ws_target(kObserverToken)), 101);
    ASSERT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 1; }));
    g.images.publish(protocol::kXrayChannel, &f);
    auto m = first.next_frame();
    ASSERT_TRUE(m);
    EXPECT_EQ(m->frame_header()["seq"], 41);
    first.close_hard();  // no close frame: the page crashed
    EXPECT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 0; }));
  }
  for (int round = 0; round < 3; ++round) {
    WsClient again;
    ASSERT_EQ(again.connect(g.port(), ws_target(kObserverToken)), 101);
    ASSERT_TRUE(again.next_of("hello"));
    auto m = again.next_frame(1000ms);
    ASSERT_TRUE(m) << "the last image is held for a page that joins late";
    EXPECT_EQ(m->frame_header()["seq"], 41);
    auto state = again.next_of("state");
    ASSERT_TRUE(state);
    EXPECT_EQ((*state)["gateway"]["clients"], 1);
    again.close_hard();
    EXPECT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 0; }));
  }
  EXPECT_EQ(g.gateway->hub_stats().connections_total, 4);
  EXPECT_EQ(g.gateway->hub_stats().bytes_pending, 0) << "nothing is held for pages that left";
}

TEST(RemoteReconnect, DroppedControllerReleasesThePedalAndTheKeyboardInstrument) {
  TestGateway g;
  {
    WsClient ctl;
    ASSERT_EQ(ctl.connect(g.port(), ws_target(kControllerToken)), 101);
    ASSERT_TRUE(ctl.next_of("hello"));
    ctl.send({{"type", "command"}, {"command", "fluoro"}, {"down", true}});
    ASSERT_TRUE(ctl.next_of("ack"));
    ctl.send({{"type", "keyboard"}, {"enable", true}});
    ASSERT_TRUE(ctl.next_of("ack"));
    EXPECT_NE(g.gateway->keyboard()->owner(), 0u);
    ctl.close_hard();
  }
  ASSERT_TRUE(eventually([&] { return g.recorder.all().size() == 2; }));
  const auto cmds = g.recorder.all();
  EXPECT_EQ(cmds[1].command, C::CMD_FLUORO_PEDAL);
  EXPECT_EQ(cmds[1].pedal_down, 0) << "a page that vanished must not leave the beam on";
  EXPECT_TRUE(eventually([&] { return g.gateway->keyboard()->owner() == 0u; }));

  // the next controller can take the instrument
  WsClient next;
  ASSERT_EQ(next.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(next.next_of("hello"));
  next.send({{"type", "keyboard"}, {"enable", true}});
  EXPECT_TRUE(next.next_of("ack"));
}

TEST(RemoteReconnect, ShutdownClosesPagesCleanly) {
  TestGateway g;
  WsClient a, b;
  ASSERT_EQ(a.connect(g.port(), ws_target(kObserverToken)), 101);
  ASSERT_EQ(b.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 2; }));
  g.gateway->stop();
  EXPECT_TRUE(eventually([&] { return a.closed() && b.closed(); }));
  WsClient late;
  EXPECT_NE(late.connect(g.port(), ws_target(kObserverToken)), 101);
}

}  // namespace
}  // namespace pcisim::remote::test
