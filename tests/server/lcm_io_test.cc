#include "server/lcm_io.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <chrono>
#include <limits>
#include <mutex>
#include <thread>

#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/clock.h"
#include "fuzz/lcm_mutants.h"
#include "realtime/allocation_count.h"

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
        lcm, state, limits, 8.0, [](pcisim_lcm::sim_status_t&) {},
        [](int b) -> const std::string& {
          static const std::string lad = "LAD", none;
          return b == 2 ? lad : none;
        });
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
  slot.force.axial_stiffness_n_per_m = 300.0;
  slot.force.torsional_stiffness_nm_per_rad = 0.002;
  ASSERT_TRUE(state.forces.push(slot));
  physics::WorldSnapshot& snap = state.snapshot_for_tx.write_slot();
  snap.step = 3;
  snap.wire_nodes_m = {{0, 0, 0}, {0.001, 0.002, 0.003}};
  snap.wire_contact = {0, 1};
  snap.wire_contact_force_n = {{0, 0, 0}, {0, -0.125, 0.5}};
  snap.tip_force_n = 0.5;
  snap.hub_force_n = 0.75;
  snap.hub_torque_nm = -2e-4;
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
    EXPECT_DOUBLE_EQ(listener.forces[0].axial_stiffness_n_per_mm, 0.3);  // the message's units
    EXPECT_DOUBLE_EQ(listener.forces[0].torsional_stiffness_nmm_per_rad, 2.0);
    EXPECT_EQ(listener.wires[0].num_nodes, 2);
    EXPECT_FLOAT_EQ(listener.wires[0].node_mm[1][2], 3.0f);
    EXPECT_EQ(listener.wires[0].contact[1], 1);
    // the wall's force on each node in N (not scaled like the positions), the tip's and the hub's
    EXPECT_FLOAT_EQ(listener.wires[0].contact_force_n[0][1], 0.0f);
    EXPECT_FLOAT_EQ(listener.wires[0].contact_force_n[1][1], -0.125f);
    EXPECT_FLOAT_EQ(listener.wires[0].contact_force_n[1][2], 0.5f);
    EXPECT_DOUBLE_EQ(listener.wires[0].tip_force_n, 0.5);
    EXPECT_DOUBLE_EQ(listener.wires[0].hub_force_n, 0.75);
    EXPECT_DOUBLE_EQ(listener.wires[0].hub_torque_nm, -2e-4);
    EXPECT_EQ(listener.wires[0].tip_branch, "LAD");
  }
  ASSERT_TRUE(wait_for(
      [&] {
        std::lock_guard lock(listener.mutex);
        return listener.statuses > 0;
      },
      2500ms))
      << "sim_status_t once a second";
}

TEST_F(LcmIoTest, StopPublishesAZeroForceLast) {
  io->stop();
  // nobody handles the instance any more: drain it here
  while (lcm.handleTimeout(50) > 0) {}
  std::lock_guard lock(listener.mutex);
  ASSERT_FALSE(listener.forces.empty());
  EXPECT_EQ(listener.forces.back().seq, -1);
  EXPECT_EQ(listener.forces.back().axial_force_n, 0.0);
  EXPECT_EQ(listener.forces.back().torque_nmm, 0.0);
}

}  // namespace
}  // namespace pcisim::server

namespace pcisim::server {
namespace {

template <class M>
void publish_raw(lcm::LCM& lcm, const char* channel, const std::vector<uint8_t>& bytes) {
  lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
}

// every malformed shape on both channels the server listens on: each counted as bad, none
// delivered, nothing thrown out of the handler; a good command after the flood still works
TEST_F(LcmIoTest, EveryMalformedShapeOnEveryChannelIsCountedAndTheServerGoesOn) {
  const auto instrument = fuzz::instrument_case();
  const auto session = fuzz::session_case();
  int64_t sent = 0;
  for (const auto& m : instrument.mutants) publish_raw<int>(lcm, protocol::kInstrumentChannel, m.bytes), ++sent;
  for (const auto& m : session.mutants) publish_raw<int>(lcm, protocol::kSessionChannel, m.bytes), ++sent;
  ASSERT_TRUE(wait_for([&] { return state.lcm_rx.load() >= sent; }, 10s));
  EXPECT_EQ(state.lcm_dropped_bad.load(), sent);
  EXPECT_FALSE(state.instrument_for_haptics.refresh()) << "a malformed sample reached the haptic loop";
  EXPECT_FALSE(state.paused.load());

  pcisim_lcm::session_command_t pause{};
  pause.command = pcisim_lcm::session_command_t::CMD_PAUSE;
  lcm.publish(protocol::kSessionChannel, &pause);
  EXPECT_TRUE(wait_for([&] { return state.paused.load(); }));
}

// a scene reload builds a new server on the same lcm::LCM: the old handlers must go with the old
// LcmIo, or every message is handled once per server that ever ran (and by a dead `this`)
TEST_F(LcmIoTest, ASecondLcmIoOnTheSameLcmHandlesEachMessageOnce) {
  io.reset();
  SharedState second;
  auto next = std::make_unique<LcmIo>(
      lcm, second, limits, 8.0, [](pcisim_lcm::sim_status_t&) {}, nullptr);
  next->start();
  pcisim_lcm::session_command_t contrast{};
  contrast.command = pcisim_lcm::session_command_t::CMD_CONTRAST;
  lcm.publish(protocol::kSessionChannel, &contrast);
  ASSERT_TRUE(wait_for([&] { return second.lcm_rx.load() >= 1; }));
  std::this_thread::sleep_for(50ms);  // time for a second delivery, if there were one
  EXPECT_EQ(second.lcm_rx.load(), 1);
  EXPECT_EQ(second.injections.load(), 1);
  EXPECT_EQ(limits.injections(), 1);
  EXPECT_EQ(state.lcm_rx.load(), 0) << "the first LcmIo still heard the bus";
  next.reset();
}

pcisim_lcm::session_command_t command(int8_t c) {
  pcisim_lcm::session_command_t m{};
  m.command = c;
  return m;
}

// resets: one per min_reset_interval_s; the rest refused and counted
TEST_F(LcmIoTest, ResetsAreRateLimited) {
  const auto reset = command(pcisim_lcm::session_command_t::CMD_RESET);
  for (int i = 0; i < 5; ++i) lcm.publish(protocol::kSessionChannel, &reset);
  ASSERT_TRUE(wait_for([&] { return state.lcm_rx.load() >= 5; }));
  EXPECT_TRUE(state.reset_requested.load());
  EXPECT_EQ(limits.resets_refused(), 4);
}

// contrast: at most max_injections_per_min in any minute, and max_contrast_ml in the session
TEST_F(LcmIoTest, ContrastIsBoundedPerMinuteAndPerSession) {
  const auto contrast = command(pcisim_lcm::session_command_t::CMD_CONTRAST);
  for (int i = 0; i < 10; ++i) lcm.publish(protocol::kSessionChannel, &contrast);
  ASSERT_TRUE(wait_for([&] { return state.lcm_rx.load() >= 10; }));
  const int per_min = SessionLimitParams{}.max_injections_per_min;
  EXPECT_EQ(state.injections.load(), per_min);
  EXPECT_EQ(limits.injections_refused(), 10 - per_min);
  EXPECT_DOUBLE_EQ(limits.contrast_ml(), per_min * 8.0);
}

TEST(SessionLimits, TheMinuteWindowAndTheSessionTotal) {
  SessionLimits l;
  SessionLimitParams p;
  p.max_injections_per_min = 2;
  p.max_contrast_ml = 25;
  l.configure(p);
  const int64_t s = 1'000'000'000;
  EXPECT_TRUE(l.allow_injection(0, 8));
  EXPECT_TRUE(l.allow_injection(10 * s, 8));
  EXPECT_FALSE(l.allow_injection(59 * s, 8)) << "a third within the first's minute";
  EXPECT_TRUE(l.allow_injection(60 * s, 8)) << "the first is a minute old";
  EXPECT_FALSE(l.allow_injection(200 * s, 8)) << "32 ml would pass the session's 25";
  EXPECT_TRUE(l.allow_injection(200 * s, 1));
  EXPECT_FALSE(l.allow_injection(300 * s, std::numeric_limits<double>::quiet_NaN()));
  EXPECT_EQ(l.injections(), 4);
  EXPECT_EQ(l.injections_refused(), 3);
  EXPECT_DOUBLE_EQ(l.contrast_ml(), 25.0);
  // the limits of a new scene apply to the same history
  p.max_contrast_ml = 100;
  l.configure(p);
  EXPECT_TRUE(l.allow_injection(400 * s, 8));
  EXPECT_DOUBLE_EQ(l.contrast_ml(), 33.0);
}

TEST(SessionLimits, ScenesLoadOncePerIntervalCountingOnlyAcceptedOnes) {
  SessionLimits l;
  const int64_t s = 1'000'000'000;
  EXPECT_TRUE(l.allow_scene_load(0));
  EXPECT_TRUE(l.allow_scene_load(1 * s)) << "nothing was accepted yet";
  l.book_scene_load(1 * s);
  EXPECT_FALSE(l.allow_scene_load(5 * s));
  EXPECT_TRUE(l.allow_scene_load(11 * s));
  EXPECT_EQ(l.scene_loads_refused(), 1);
}

// a C-arm flood: the x-ray thread moves once per interval to the newest target (tested with the
// loop in tests/integration); here the receive side writes whole targets and counts them
TEST_F(LcmIoTest, CarmTargetsAreWrittenWholeNewestLast) {
  for (int i = 1; i <= 20; ++i) {
    auto c = command(pcisim_lcm::session_command_t::CMD_CARM);
    c.primary_angle_deg = i;
    c.secondary_angle_deg = -i;
    lcm.publish(protocol::kSessionChannel, &c);
  }
  ASSERT_TRUE(wait_for([&] { return state.lcm_rx.load() >= 20; }));
  EXPECT_EQ(state.carm_requests.load(), 20);
  EXPECT_EQ(state.carm_target_seq.load(), 40) << "even: no write in progress";
  EXPECT_DOUBLE_EQ(state.carm_target_primary_deg.load(), 20.0);
  EXPECT_DOUBLE_EQ(state.carm_target_secondary_deg.load(), -20.0);
}

}  // namespace
}  // namespace pcisim::server

namespace pcisim::server {
namespace {

// the soft-tissue scene's receive side: PCISIM_PROBE instead of PCISIM_INSTRUMENT
class LcmIoProbeTest : public ::testing::Test {
 protected:
  lcm::LCM lcm{"memq://"};
  SharedState state;
  SessionLimits limits;
  std::unique_ptr<LcmIo> io;

  void SetUp() override {
    ASSERT_TRUE(lcm.good());
    // the beam physics linearised at: scene +y (the probe's default pose)
    state.probe_beam_x = 0.0, state.probe_beam_y = 1.0, state.probe_beam_z = 0.0;
    io = std::make_unique<LcmIo>(
        lcm, state, limits, 8.0, [](pcisim_lcm::sim_status_t&) {},
        [](int) -> const std::string& {
          static const std::string none;
          return none;
        },
        LcmIo::Instrument::kProbe);
    io->start();
  }
  static pcisim_lcm::probe_state_t probe(int64_t utime_us, double y_mm, const double wxyz[4]) {
    pcisim_lcm::probe_state_t m{};
    m.utime = utime_us;
    m.seq = utime_us;
    m.position_mm[0] = 3.0, m.position_mm[1] = y_mm, m.position_mm[2] = 15.0;
    for (int k = 0; k < 4; ++k) m.orientation_wxyz[k] = wxyz[k];
    return m;
  }
  InstrumentSlot next_slot() {
    EXPECT_TRUE(wait_for([&] { return state.instrument_for_haptics.refresh(); }));
    return state.instrument_for_haptics.read_slot();
  }
};

TEST_F(LcmIoProbeTest, ThePoseReachesPhysicsAndTheDepthAlongTheLinearisedBeamTheHapticLoop) {
  const double down[4] = {0.5, -0.5, -0.5, -0.5};  // beam +y
  {
    const auto m = probe(1'000'000, -20.0, down);
    lcm.publish(protocol::kProbeChannel, &m);
  }
  InstrumentSlot a = next_slot();
  EXPECT_TRUE(a.probe_present);
  EXPECT_DOUBLE_EQ(a.sample.insertion_m, -0.020);
  EXPECT_EQ(a.sample.insertion_rate_m_per_s, 0.0) << "no rate from one sample";
  ASSERT_TRUE(state.instrument_for_physics.refresh());
  EXPECT_DOUBLE_EQ(state.instrument_for_physics.read_slot().probe_position_m[2], 0.015);
  EXPECT_DOUBLE_EQ(state.instrument_for_physics.read_slot().probe_orientation_wxyz[0], 0.5);

  // 0.1 mm deeper 1 ms later by the sender's clock: 0.1 m/s, whenever it arrives
  {
    const auto m = probe(1'001'000, -19.9, down);
    lcm.publish(protocol::kProbeChannel, &m);
  }
  InstrumentSlot b = next_slot();
  EXPECT_NEAR(b.sample.insertion_rate_m_per_s, 0.1, 1e-9);

  // turned 20 deg in place about its lateral axis: the depth the haptic loop sees stays
  const Eigen::Quaterniond q = Eigen::Quaterniond(down[0], down[1], down[2], down[3]) *
                               Eigen::Quaterniond(Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitY()));
  const double turned[4] = {q.w(), q.x(), q.y(), q.z()};
  {
    const auto m = probe(1'002'000, -19.9, turned);
    lcm.publish(protocol::kProbeChannel, &m);
  }
  InstrumentSlot c = next_slot();
  EXPECT_NEAR(c.sample.insertion_m, -0.0199, 1e-12);
  EXPECT_NEAR(c.sample.insertion_rate_m_per_s, 0.0, 1e-9);
  EXPECT_EQ(state.lcm_dropped_bad.load(), 0);
}

TEST_F(LcmIoProbeTest, ANanPoseIsCountedAndDroppedAndTheWireInstrumentIsNotHeard) {
  const double down[4] = {0.5, -0.5, -0.5, -0.5};
  pcisim_lcm::probe_state_t bad = probe(1'000'000, -20.0, down);
  bad.position_mm[1] = std::numeric_limits<double>::quiet_NaN();
  lcm.publish(protocol::kProbeChannel, &bad);
  pcisim_lcm::instrument_state_t wire{};
  wire.insertion_mm = 5.0;
  lcm.publish(protocol::kInstrumentChannel, &wire);
  ASSERT_TRUE(wait_for([&] { return state.instrument_rejected.load() == 1; }));
  EXPECT_EQ(state.lcm_dropped_bad.load(), 1);
  std::this_thread::sleep_for(50ms);
  EXPECT_FALSE(state.instrument_for_haptics.refresh()) << "neither the NaN probe nor the wire reached the loop";
}

// the send thread's streams allocate nothing once their encode buffer has its size (issue #36
// item 5: lcm-cpp's publish of a message allocates a buffer per call): 1 010 messages, 0
// operator new (liblcm's own transport mallocs are not counted: memq copies each message)
TEST(LcmIoPublish, ForceCommandsAndWireStatesAllocateNothingOnceWarm) {
  lcm::LCM lcm("memq://");
  SharedState state;
  SessionLimits limits;
  LcmIo io(
      lcm, state, limits, 8.0, [](pcisim_lcm::sim_status_t&) {},
      [](int) -> const std::string& {
        static const std::string name = "a branch name longer than fifteen characters";
        return name;
      });
  physics::WorldSnapshot snap;
  snap.wire_nodes_m.assign(300, Eigen::Vector3d(0.001, 0.002, 0.003));
  snap.wire_contact.assign(300, 1);
  snap.wire_contact_force_n.assign(300, Eigen::Vector3d(0.0, 0.01, 0.0));
  snap.tip_branch = 2;
  auto push = [&](int n) {
    for (int k = 0; k < n; ++k) {
      ForceSlot slot;
      slot.tick = k;
      slot.force.axial_force_n = 0.1 * k;
      EXPECT_TRUE(state.forces.push(slot));
    }
  };
  push(10);  // warm: the messages and the buffer take their sizes
  io.publish_forces();
  io.publish_wire(snap);
  const int64_t sent_before = state.lcm_tx.load();
  {
    pcisim::realtime::AllocationCount count;
    for (int round = 0; round < 10; ++round) {
      push(100);
      io.publish_forces();
      io.publish_wire(snap);
    }
    EXPECT_EQ(count.allocations(), 0);
  }
  EXPECT_EQ(state.lcm_tx.load() - sent_before, 10 * 101);
}

}  // namespace
}  // namespace pcisim::server
