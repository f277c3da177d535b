#include "server/lcm_io.h"

#include <gtest/gtest.h>

#include <chrono>
#include <limits>
#include <mutex>
#include <thread>

#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "server/realtime/clock.h"

namespace pcisim::server {
namespace {

using namespace std::chrono_literals;

// collects what the server side publishes; handlers run on LcmIo's receive thread
struct Listener {
  std::mutex mutex;
  std::vector<pcisim_lcm::force_command_t> forces;
  std::vector<pcisim_lcm::wire_state_t> wires;
  int statuses = 0;
  void on_force(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::force_command_t m;
    ASSERT_TRUE(protocol::decode_checked(*r, m));
    std::lock_guard lock(mutex);
    forces.push_back(m);
  }
  void on_wire(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::wire_state_t m;
    ASSERT_TRUE(protocol::decode_checked(*r, m));
    std::lock_guard lock(mutex);
    wires.push_back(m);
  }
  void on_status(const lcm::ReceiveBuffer*, const std::string&) {
    std::lock_guard lock(mutex);
    ++statuses;
  }
};

template <class Pred>
bool wait_for(Pred pred, std::chrono::milliseconds timeout = 3000ms) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (pred()) return true;
    std::this_thread::sleep_for(2ms);
  }
  return pred();
}

class LcmIoTest : public ::testing::Test {
 protected:
  lcm::LCM lcm{"memq://"};
  SharedState state;
  SessionLimits limits;
  Listener listener;
  std::unique_ptr<LcmIo> io;

  void SetUp() override {
    ASSERT_TRUE(lcm.good());
    lcm.subscribe(protocol::kForceChannel, &Listener::on_force, &listener);
    lcm.subscribe(protocol::kWireChannel, &Listener::on_wire, &listener);
    lcm.subscribe(protocol::kStatusChannel, &Listener::on_status, &listener);
    io = std::make_unique<LcmIo>(
        lcm, state, limits, 8.0, [] { return pcisim_lcm::sim_status_t{}; },
        [](int b) { return b == 2 ? std::string("LAD") : std::string(); });
    io->start();
  }
};

TEST_F(LcmIoTest, InstrumentSamplesReachBothLoopsInSiUnits) {
  pcisim_lcm::instrument_state_t m{};
  m.seq = 5;
  m.insertion_mm = 12.0;
  m.rotation_rad = 0.5;
  lcm.publish(protocol::kInstrumentChannel, &m);
  ASSERT_TRUE(wait_for([&] { return state.instrument_for_haptics.refresh(); }));
  EXPECT_EQ(state.instrument_for_haptics.read_slot().seq, 5);
  EXPECT_DOUBLE_EQ(state.instrument_for_haptics.read_slot().sample.insertion_m, 0.012);
  EXPECT_GT(state.instrument_for_haptics.read_slot().sample.received_us, 0);
  ASSERT_TRUE(state.instrument_for_physics.refresh());
  EXPECT_DOUBLE_EQ(state.instrument_for_physics.read_slot().sample.rotation_rad, 0.5);
  EXPECT_EQ(state.lcm_dropped_bad.load(), 0);
}

TEST_F(LcmIoTest, BadMessagesAreCountedAndDroppedNeverDelivered) {
  // garbage, a wrong type (fingerprint), a truncated message and a NaN field
  const uint8_t garbage[] = {1, 2, 3};
  lcm.publish(protocol::kInstrumentChannel, garbage, sizeof garbage);
  pcisim_lcm::force_command_t wrong{};
  lcm.publish(protocol::kInstrumentChannel, &wrong);
  pcisim_lcm::instrument_state_t m{};
  std::vector<uint8_t> bytes(m.getEncodedSize());
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  lcm.publish(protocol::kInstrumentChannel, bytes.data(), static_cast<unsigned>(bytes.size() - 8));
  m.insertion_mm = std::numeric_limits<double>::quiet_NaN();
  lcm.publish(protocol::kInstrumentChannel, &m);
  lcm.publish(protocol::kSessionChannel, garbage, sizeof garbage);

  ASSERT_TRUE(wait_for([&] { return state.lcm_dropped_bad.load() == 5; })) << state.lcm_dropped_bad.load();
  EXPECT_EQ(state.lcm_rx.load(), 5);
  EXPECT_FALSE(state.instrument_for_haptics.refresh()) << "nothing bad reached the haptic loop";
}

TEST_F(LcmIoTest, ForceCommandsWireStateAndStatusGoOut) {
  ForceSlot slot;
  slot.tick = 41;
  slot.instrument_seq = 9;
  slot.force.axial_force_n = 0.25;
  slot.force.torque_nm = 0.001;
  ASSERT_TRUE(state.forces.push(slot));
  physics::WorldSnapshot& snap = state.snapshot_for_tx.write_slot();
  snap.step = 3;
  snap.wire_nodes_m = {{0, 0, 0}, {0.001, 0.002, 0.003}};
  snap.wire_contact = {0, 1};
  snap.tip_branch = 2;
  state.snapshot_for_tx.publish();

  ASSERT_TRUE(wait_for([&] {
    std::lock_guard lock(listener.mutex);
    return !listener.forces.empty() && !listener.wires.empty();
  }));
  {
    std::lock_guard lock(listener.mutex);
    EXPECT_EQ(listener.forces[0].seq, 41);
    EXPECT_EQ(listener.forces[0].instrument_seq, 9);
    EXPECT_DOUBLE_EQ(listener.forces[0].axial_force_n, 0.25);
    EXPECT_DOUBLE_EQ(listener.forces[0].torque_nmm, 1.0);
    EXPECT_EQ(listener.wires[0].num_nodes, 2);
    EXPECT_FLOAT_EQ(listener.wires[0].node_mm[1][2], 3.0f);
    EXPECT_EQ(listener.wires[0].contact[1], 1);
    EXPECT_EQ(listener.wires[0].tip_branch, "LAD");
  }
  ASSERT_TRUE(wait_for([&] {
    std::lock_guard lock(listener.mutex);
    return listener.statuses > 0;
  }, 2500ms)) << "sim_status_t once a second";
}

TEST_F(LcmIoTest, StopPublishesAZeroForceLast) {
  io->stop();
  // nobody handles the instance any more: drain it here
  while (lcm.handleTimeout(50) > 0) {
  }
  std::lock_guard lock(listener.mutex);
  ASSERT_FALSE(listener.forces.empty());
  EXPECT_EQ(listener.forces.back().seq, -1);
  EXPECT_EQ(listener.forces.back().axial_force_n, 0.0);
  EXPECT_EQ(listener.forces.back().torque_nmm, 0.0);
}

}  // namespace
}  // namespace pcisim::server
