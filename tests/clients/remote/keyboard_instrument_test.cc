// The keyboard instrument: held arrow keys move the wire through real instrument samples on the
// bus, only for the page that enabled it, and never while hardware is active.
#include <gtest/gtest.h>

#include "clients/remote/keyboard_instrument.h"
#include "remote_test_support.h"
#include "realtime/clock.h"

namespace pcisim::remote::test {
namespace {

using I = pcisim_lcm::instrument_state_t;

struct InstrumentRecorder {
  std::mutex mutex;
  std::vector<I> samples;
  void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    I m;
    if (!protocol::decode_checked(*rbuf, m)) return;
    std::lock_guard lock(mutex);
    samples.push_back(m);
  }
  std::vector<I> of(int32_t device) {
    std::lock_guard lock(mutex);
    std::vector<I> out;
    for (const auto& s : samples)
      if (s.device_id == device) out.push_back(s);
    return out;
  }
};

TEST(RemoteKeyboard, HeldKeysInsertAndRotateThroughInstrumentSamples) {
  GatewayOptions o;
  o.keyboard.rate_hz = 500;
  o.keyboard.insert_mm_s = 20;
  TestGateway g(o, false);
  InstrumentRecorder rec;
  g.control.subscribe(protocol::kInstrumentChannel, &InstrumentRecorder::on, &rec);
  g.gateway->start();
  WsClient ctl, other;
  ASSERT_EQ(ctl.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_EQ(other.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(ctl.next_of("hello") && other.next_of("hello"));
  std::this_thread::sleep_for(100ms);
  EXPECT_TRUE(rec.of(o.keyboard.device_id).empty()) << "nothing is published until a page enables it";

  ctl.send({{"type", "keyboard"}, {"enable", true}});
  ASSERT_TRUE(ctl.next_of("ack"));
  other.send({{"type", "keyboard"}, {"enable", true}});
  auto busy = other.next_of("error");
  ASSERT_TRUE(busy);
  EXPECT_EQ((*busy)["code"], "instrument_busy");
  other.send({{"type", "keys"}, {"insert", 1}});
  auto not_owner = other.next_of("error");
  ASSERT_TRUE(not_owner);
  EXPECT_EQ((*not_owner)["code"], "not_owner");

  // hold "up" for ~0.5 s (resent as the page does), then let go
  const auto held_from = std::chrono::steady_clock::now();
  for (int i = 0; i < 4; ++i) {
    ctl.send({{"type", "keys"}, {"insert", 1}, {"rotate", -0.5}});
    std::this_thread::sleep_for(125ms);
  }
  ctl.send({{"type", "keys"}, {"insert", 0}, {"rotate", 0}});
  const double held_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - held_from).count();
  std::this_thread::sleep_for(200ms);
  const auto s = rec.of(o.keyboard.device_id);
  // 500 samples a second on a quiet machine; the count is not the point, the motion is
  ASSERT_GT(s.size(), 20u) << "samples flow while a page holds the instrument";
  EXPECT_EQ(s.front().status, I::STATUS_OK);
  const double moved = s.back().insertion_mm - s.front().insertion_mm;
  // 20 mm/s for as long as the key was held (a late key message may pause it, never speed it up)
  EXPECT_GT(moved, 0.6 * 20 * held_s) << "held " << held_s << " s";
  EXPECT_LT(moved, 20 * held_s + 2) << "held " << held_s << " s";
  EXPECT_LT(s.back().rotation_rad, -0.3);  // 1 rad/s backwards
  for (size_t i = 1; i < s.size(); ++i) {
    EXPECT_GT(s[i].seq, s[i - 1].seq);
    EXPECT_GE(s[i].insertion_mm, s[i - 1].insertion_mm - 1e-9) << "only forward while 'up' is held";
  }
  EXPECT_DOUBLE_EQ(s.back().insertion_rate_mm_s, 0.0) << "released keys stop the wire";

  ctl.send({{"type", "keyboard"}, {"enable", false}});
  ASSERT_TRUE(ctl.next_of("ack"));
  std::this_thread::sleep_for(50ms);
  const size_t n = rec.of(o.keyboard.device_id).size();
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(rec.of(o.keyboard.device_id).size(), n) << "disabled: silent";
}

TEST(RemoteKeyboard, KeysThatStopArrivingCountAsReleased) {
  GatewayOptions o;
  o.keyboard.key_timeout_ns = 150'000'000;
  TestGateway g(o);
  WsClient ctl;
  ASSERT_EQ(ctl.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(ctl.next_of("hello"));
  ctl.send({{"type", "keyboard"}, {"enable", true}});
  ASSERT_TRUE(ctl.next_of("ack"));
  ctl.send({{"type", "keys"}, {"insert", 1}});  // pressed once, then the page froze
  std::this_thread::sleep_for(400ms);
  const double a = g.gateway->keyboard()->insertion_mm();
  std::this_thread::sleep_for(300ms);
  EXPECT_DOUBLE_EQ(g.gateway->keyboard()->insertion_mm(), a);
  EXPECT_GT(a, 1.5);  // moved for about the timeout
  EXPECT_LT(a, 6);
}

TEST(RemoteKeyboard, HardwareInstrumentWins) {
  TestGateway g;
  WsClient ctl;
  ASSERT_EQ(ctl.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(ctl.next_of("hello"));
  std::atomic<bool> hardware{true};
  std::thread device([&] {
    I m{};
    m.device_id = 1;
    for (int64_t seq = 0; hardware; ++seq) {
      m.seq = seq;
      g.control.publish(protocol::kInstrumentChannel, &m);
      std::this_thread::sleep_for(5ms);
    }
  });
  ASSERT_TRUE(eventually([&] { return g.gateway->tracker().other_instrument_active(realtime::monotonic_ns()); }));
  ctl.send({{"type", "keyboard"}, {"enable", true}});
  auto err = ctl.next_of("error");
  ASSERT_TRUE(err);
  EXPECT_EQ((*err)["code"], "instrument_busy");
  hardware = false;
  device.join();
  std::this_thread::sleep_for(300ms);  // silent for longer than the activity window

  ctl.send({{"type", "keyboard"}, {"enable", true}});
  ASSERT_TRUE(ctl.next_of("ack"));
  // the hardware comes back: the keyboard instrument stops and says why
  hardware = true;
  std::thread device2([&] {
    I m{};
    m.device_id = 1;
    for (int64_t seq = 0; hardware; ++seq) {
      m.seq = seq;
      g.control.publish(protocol::kInstrumentChannel, &m);
      std::this_thread::sleep_for(5ms);
    }
  });
  EXPECT_TRUE(eventually([&] { return g.gateway->keyboard()->owner() == 0; }));
  EXPECT_EQ(g.gateway->keyboard()->stop_reason(), "another instrument became active");
  hardware = false;
  device2.join();
}

}  // namespace
}  // namespace pcisim::remote::test
