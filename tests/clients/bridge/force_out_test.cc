// The force back to the hand (issue #37): the force line's format and ranges, the gate that
// zeroes the force first in every fault, the box simulator's watchdog, and the closed loop over a
// pseudo-terminal: a server's force commands reach the box, and each fault (the server silent, a
// command flagged stale, a non-finite command, the box silent) turns into zero force at the box
// within 50 ms.
#include <gtest/gtest.h>

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "clients/bridge/box_simulator.h"
#include "clients/bridge/bridge.h"
#include "clients/bridge/force_gate.h"
#include "clients/bridge/force_line.h"
#include "clients/bridge/serial_device.h"
#include "clients/bridge/latency_histogram.h"
#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "protocol/channels.h"
#include "realtime/clock.h"
#include "realtime/allocation_count.h"

namespace pcisim::clients {
namespace {

using F = pcisim_lcm::force_command_t;

std::string line_of(const ForceSetpoint& f, int64_t seq) {
  char buf[kForceLineMaxBytes];
  return std::string(buf, format_force_line(f, seq, buf));
}

TEST(ForceLine, WritesMilliNewtonsAndMicroNewtonMetresRoundedAndClamped) {
  EXPECT_EQ(line_of({0.5, 2.0}, 7), "F 500 2000 7\n");  // 2 N mm = 2000 uN m
  EXPECT_EQ(line_of({-0.0125, -0.0004}, 8), "F -13 0 8\n") << "half away from zero";
  EXPECT_EQ(line_of({0.0015, 0.0015}, 9), "F 2 2 9\n");
  EXPECT_EQ(line_of({50.0, 5000.0}, 10), "F 20000 1000000 10\n") << "clamped to 20 N and 1 N m";
  EXPECT_EQ(line_of({-50.0, -5000.0}, 11), "F -20000 -1000000 11\n");
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(line_of({nan, inf}, 12), "F 0 0 12\n") << "nothing non-finite reaches a box";
  // what the box reads back
  ForceLine f;
  ASSERT_TRUE(parse_force_line("F -13 2000 99\r", f));
  EXPECT_EQ(f.axial_mn, -13);
  EXPECT_EQ(f.torque_unm, 2000);
  EXPECT_EQ(f.seq, 99);
  for (const char* bad :
       {"", "F", "F 1 2", "F 1 2 3 4", "E 1 2 3", "F1 2 3", "F 1.5 2 3", "F 20001 0 1", "F 0 -1000001 1", "F a b c"})
    EXPECT_FALSE(parse_force_line(bad, f)) << "'" << bad << "'";
  // formatting allocates nothing
  realtime::AllocationCount count;
  char buf[kForceLineMaxBytes];
  for (int i = 0; i < 100; ++i) format_force_line({0.1 * i, -0.2 * i}, i, buf);
  EXPECT_EQ(count.allocations(), 0);
}

// the stiffness and the answered sample ride with the force; a negative stiffness is no spring,
// a non-finite one a fault, and a fault carries neither
TEST(ForceGate, PassesTheStiffnessAndTheAnsweredSample) {
  ForceGateInput in;
  in.device_ok = true;
  in.now_ns = 1'000'000'000;
  in.last_command_ns = in.now_ns - 1'000'000;
  in.torque_nmm = 2.0;
  in.axial_stiffness_n_per_mm = 0.4;
  in.torsional_stiffness_nmm_per_rad = 3.0;
  in.instrument_seq = 77;
  ForceSetpoint out;
  ASSERT_EQ(gate_force(in, &out), ForceGateState::kRendering);
  EXPECT_EQ(out.axial_stiffness_n_per_mm, 0.4);
  EXPECT_EQ(out.torsional_stiffness_nmm_per_rad, 3.0);
  EXPECT_EQ(out.sample_seq, 77);
  in.torsional_stiffness_nmm_per_rad = -3.0;
  ASSERT_EQ(gate_force(in, &out), ForceGateState::kRendering);
  EXPECT_EQ(out.torsional_stiffness_nmm_per_rad, 0.0);
  in.axial_stiffness_n_per_mm = std::numeric_limits<double>::infinity();
  EXPECT_EQ(gate_force(in, &out), ForceGateState::kNotFinite);
  EXPECT_EQ(out.axial_stiffness_n_per_mm, 0.0);
  EXPECT_EQ(out.sample_seq, -1);
}

TEST(ForceGate, RendersAFreshHealthyCommandAndZeroesEveryFault) {
  ForceGateInput in;
  in.device_ok = true;
  in.now_ns = 1'000'000'000;
  in.last_command_ns = in.now_ns - 1'000'000;
  in.axial_n = 0.7;
  in.torque_nmm = -1.5;
  ForceSetpoint out;
  ASSERT_EQ(gate_force(in, &out), ForceGateState::kRendering);
  EXPECT_EQ(out.axial_n, 0.7);
  EXPECT_EQ(out.torque_nmm, -1.5);
  // the server's own shaping (clamped, faded, ramping) is rendered as sent
  for (const int32_t flags : {int32_t{F::FLAG_CLAMPED}, int32_t{F::FLAG_FADED}, int32_t{F::FLAG_RAMPING}}) {
    ForceGateInput shaped = in;
    shaped.flags = flags;
    EXPECT_EQ(gate_force(shaped, &out), ForceGateState::kRendering) << flags;
  }
  struct Case {
    ForceGateState expected;
    void (*change)(ForceGateInput&);
  };
  const Case faults[] = {
      {ForceGateState::kDeviceFault, [](ForceGateInput& i) { i.device_ok = false; }},
      {ForceGateState::kNoCommand, [](ForceGateInput& i) { i.last_command_ns = -1; }},
      {ForceGateState::kServerSilent, [](ForceGateInput& i) { i.last_command_ns = i.now_ns - kServerSilentNs - 1; }},
      {ForceGateState::kFlaggedStale, [](ForceGateInput& i) { i.flags = F::FLAG_STALE; }},
      {ForceGateState::kFlaggedFault,
       [](ForceGateInput& i) { i.flags = int32_t{F::FLAG_FAULT} | int32_t{F::FLAG_FADED}; }},
      {ForceGateState::kNotFinite, [](ForceGateInput& i) { i.torque_nmm = std::nan(""); }},
  };
  for (const Case& c : faults) {
    ForceGateInput faulty = in;
    c.change(faulty);
    out = {1.0, 1.0};
    EXPECT_EQ(gate_force(faulty, &out), c.expected) << describe(c.expected);
    EXPECT_EQ(out.axial_n, 0.0) << describe(c.expected);
    EXPECT_EQ(out.torque_nmm, 0.0) << describe(c.expected);
  }
  // still fresh at exactly the silence threshold
  ForceGateInput edge = in;
  edge.last_command_ns = edge.now_ns - kServerSilentNs;
  EXPECT_EQ(gate_force(edge, &out), ForceGateState::kRendering);
}

// the box applies a force line until the next and, by its watchdog, zero once none came for 50 ms;
// a SerialDevice on its port writes the lines
TEST(BoxSimulator, AppliesEachForceLineAndItsWatchdogZeroesItAfter50Ms) {
  BoxSimulator box(TraineeScript::parse(TraineeScript::builtin_text(), "built-in"), SerialCalibration{});
  SerialDevice device(box.port(), 115200, SerialCalibration{});
  EXPECT_EQ(box.applied_axial_n(0.0), 0.0) << "nothing before the first line";
  EXPECT_TRUE(box.watchdog_tripped(0.0));
  ASSERT_TRUE(device.render({0.25, -3.0}, 1));
  // the pty delivers on a kernel worker: read until the line is there (at most 2 s)
  for (int i = 0; i < 2000 && box.force_lines() == 0; ++i) {
    box.listen(1.000);
    usleep(1000);
  }
  box.step(1.000);
  EXPECT_EQ(box.force_lines(), 1);
  EXPECT_DOUBLE_EQ(box.applied_axial_n(1.000), 0.25);
  EXPECT_DOUBLE_EQ(box.applied_torque_nmm(1.000), -3.0);
  EXPECT_DOUBLE_EQ(box.applied_axial_n(1.000 + 0.049), 0.25);
  EXPECT_EQ(box.applied_axial_n(1.000 + 0.051), 0.0) << "the watchdog";
  EXPECT_EQ(box.applied_torque_nmm(1.000 + 0.051), 0.0);
  // the box's encoder lines reach the device as the script's motion
  InstrumentReading r;
  bool read = false;
  for (int i = 0; i < 2000 && !read; ++i) {
    read = device.read(1.0, r);
    if (!read) usleep(1000);
  }
  EXPECT_TRUE(read);
  EXPECT_GT(box.lines_sent(), 0);
  EXPECT_EQ(device.malformed(), 0);
  EXPECT_EQ(box.malformed(), 0);
}

// a force line per tick allocates nothing on the serial device, and a box that is unplugged
// (the pty closed) stops the writes: the device is in fault, and the box's watchdog is what zeroes
// its actuators
TEST(BoxSimulator, ForceLinesAllocateNothingAndAnUnpluggedBoxTakesNoMore) {
  auto box = std::make_unique<BoxSimulator>(TraineeScript::parse(TraineeScript::builtin_text(), "built-in"),
                                            SerialCalibration{});
  SerialDevice device(box->port(), 115200, SerialCalibration{});
  ASSERT_TRUE(device.render({0.1, 0.1}, 0));  // the first write warms up what libc keeps
  long allocations = -1;
  {
    realtime::AllocationCount count;
    for (int i = 1; i <= 200; ++i) device.render({0.001 * i, -0.002 * i}, i);
    allocations = count.allocations();
  }
  EXPECT_EQ(allocations, 0);
  for (int i = 0; i < 2000 && box->force_lines() < 201; ++i) {
    box->listen(0.0);
    usleep(1000);
  }
  EXPECT_EQ(box->force_lines(), 201);
  box.reset();  // unplugged
  InstrumentReading r;
  EXPECT_FALSE(device.read(0.1, r));
  EXPECT_TRUE(device.unplugged());
  EXPECT_FALSE(device.render({0.5, 0.0}, 300));
}

// the closed loop: a "server" thread publishes force commands on memq through phases, the box
// thread steps at 1 kHz (sending the script's motion, reading the force), the bridge runs between
// them on the serial device. Each phase's force arrives; each fault is zero at the box within 50 ms
TEST(ForceOut, EachFaultIsZeroForceAtTheBoxWithin50Ms) {
  lcm::LCM lcm("memq://");
  BoxSimulator box(TraineeScript::parse(TraineeScript::builtin_text(), "built-in"), SerialCalibration{});
  SerialDevice device(box.port(), 115200, SerialCalibration{});
  const int64_t t0_ns = realtime::monotonic_ns();
  auto now_s = [&] { return (realtime::monotonic_ns() - t0_ns) * 1e-9; };
  // the server's phases: [start, end) s, axial N, flags, a NaN command instead
  struct Phase {
    double start_s, end_s, axial_n;
    int32_t flags;
    bool nan;
  };
  const Phase phases[] = {
      {0.00, 0.25, 0.5, 0, false},              // rendering (0.25-0.35: the server silent)
      {0.35, 0.45, 0.6, 0, false},              // rendering
      {0.45, 0.55, 0.9, F::FLAG_STALE, false},  // stale
      {0.55, 0.65, 0.8, 0, false},              // rendering
      {0.65, 0.75, 0.0, 0, true},               // NaN commands (refused by the checks: silence)
      {0.75, 0.95, 0.3, 0, false},              // rendering; the box goes silent at 0.85
  };
  constexpr double kBoxSilentS = 0.85, kEndS = 1.00;
  std::atomic<bool> done{false};
  std::thread server([&] {
    F m{};
    for (int64_t seq = 0; !done; ++seq) {
      const double t = now_s();
      for (const Phase& p : phases) {
        if (t < p.start_s || t >= p.end_s) continue;
        m.seq = seq;
        m.axial_force_n = p.nan ? std::nan("") : p.axial_n;
        m.torque_nmm = 2.0;
        m.flags = p.flags;
        lcm.publish(protocol::kForceChannel, &m);
      }
      usleep(1000);
    }
  });
  std::thread box_thread([&] {
    while (!done) {
      const double t = now_s();
      if (t < kBoxSilentS)
        box.step(t);
      else
        box.listen(t);
      usleep(1000);
    }
  });
  BridgeOptions o;
  o.duration_s = kEndS;
  o.log_each_second = false;
  Bridge bridge(lcm, device, o);
  std::atomic<bool> stop{false};
  const BridgeStats stats = bridge.run(stop);
  done = true;
  server.join();
  box_thread.join();

  const auto& log = box.log();
  ASSERT_GT(log.size(), 500u);
  // the force in a window, and the first zero line at or after a fault's start
  auto all_in = [&](double from, double to, int64_t mn) {
    int n = 0;
    for (const BoxForceSample& s : log)
      if (s.t_s >= from && s.t_s < to) {
        EXPECT_EQ(s.line.axial_mn, mn) << "at " << s.t_s << " s";
        ++n;
      }
    EXPECT_GT(n, 20) << "lines in [" << from << ", " << to << ")";
  };
  auto zero_after = [&](double fault_s) {
    for (const BoxForceSample& s : log)
      if (s.t_s >= fault_s && s.line.axial_mn == 0 && s.line.torque_unm == 0) return s.t_s - fault_s;
    return 1e9;
  };
  all_in(0.10, 0.24, 500);
  all_in(0.38, 0.45, 600);  // rendering again just before the stale commands
  const double silent_s = zero_after(0.25), stale_s = zero_after(0.45), nan_s = zero_after(0.65),
               box_silent_s = zero_after(kBoxSilentS);
  std::printf(
      "zero force at the box after: the server silent %.1f ms, a stale command %.1f ms, NaN commands %.1f ms, the "
      "box silent %.1f ms; %lld lines, %lld zeroed ticks\n",
      1e3 * silent_s, 1e3 * stale_s, 1e3 * nan_s, 1e3 * box_silent_s, static_cast<long long>(log.size()),
      static_cast<long long>(stats.force_zeroed));
  EXPECT_LT(silent_s, 0.050);
  EXPECT_LT(stale_s, 0.050);
  all_in(0.48, 0.55, 0);  // stale: zero throughout
  all_in(0.58, 0.65, 800);
  EXPECT_LT(nan_s, 0.050);
  all_in(0.78, 0.85, 300);
  // the box silent: the bridge's device faults after the serial timeout (30 ms) and sends zero
  EXPECT_LT(box_silent_s, 0.050);
  EXPECT_EQ(box.malformed(), 0);
  EXPECT_EQ(device.force_lines_dropped(), 0);
}

TEST(LatencyHistogram, PercentilesAreTheUpperEdgeOfTheirBinAndNothingIsAllocated) {
  LatencyHistogram h;
  EXPECT_EQ(h.percentile_us(0.5), 0.0);
  realtime::AllocationCount count;
  for (int i = 0; i < 1000; ++i) h.add(i < 990 ? 105.0 : 3000.0);  // 99 % at 105 us, 1 % at 3 ms
  h.add(25000.0);                                                  // beyond the bins
  EXPECT_EQ(count.allocations(), 0);
  EXPECT_EQ(h.count(), 1001);
  EXPECT_DOUBLE_EQ(h.percentile_us(0.5), 110.0);   // the 100-110 us bin
  EXPECT_DOUBLE_EQ(h.percentile_us(0.98), 110.0);  // 990 of the 1001 values
  EXPECT_DOUBLE_EQ(h.percentile_us(0.995), 3010.0);
  EXPECT_DOUBLE_EQ(h.percentile_us(1.0), 25000.0);  // the overflow bin reports the max
  EXPECT_DOUBLE_EQ(h.max_us(), 25000.0);
}

// a server that answers every instrument sample at once (instrument_seq = its seq): the bridge
// measures each sample's round trip and its way on to the box's port
struct EchoServer {
  lcm::LCM* lcm = nullptr;
  void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    pcisim_lcm::instrument_state_t m;
    if (m.decode(rbuf->data, 0, rbuf->data_size) < 0) return;
    F f{};
    f.seq = m.seq;
    f.instrument_seq = m.seq;
    f.axial_force_n = 0.2;
    lcm->publish(protocol::kForceChannel, &f);
  }
};

TEST(ForceOut, TheBridgeMeasuresEachSamplesRoundTripAndItsWayToTheDevice) {
  lcm::LCM lcm("memq://");
  EchoServer echo{&lcm};
  lcm.subscribe(protocol::kInstrumentChannel, &EchoServer::on, &echo);
  BoxSimulator box(TraineeScript::parse(TraineeScript::builtin_text(), "built-in"), SerialCalibration{});
  SerialDevice device(box.port(), 115200, SerialCalibration{});
  std::atomic<bool> done{false};
  const int64_t t0_ns = realtime::monotonic_ns();
  std::thread box_thread([&] {
    while (!done) {
      box.step((realtime::monotonic_ns() - t0_ns) * 1e-9);
      usleep(1000);
    }
  });
  BridgeOptions o;
  o.duration_s = 1.0;
  o.log_each_second = false;
  Bridge bridge(lcm, device, o);
  std::atomic<bool> stop{false};
  const BridgeStats s = bridge.run(stop);
  done = true;
  box_thread.join();
  const LatencyHistogram& back = s.sample_to_force;
  const LatencyHistogram& out = s.sample_to_device;
  std::printf(
      "memq: sample -> force back p50 %.0f / p99 %.0f / max %.0f us over %lld; -> device write p50 %.0f / p99 "
      "%.0f us over %lld\n",
      back.percentile_us(0.5), back.percentile_us(0.99), back.max_us(), static_cast<long long>(back.count()),
      out.percentile_us(0.5), out.percentile_us(0.99), static_cast<long long>(out.count()));
  // nearly every sample is answered, each counted once; the write follows the answer
  EXPECT_GT(back.count(), 800);
  EXPECT_LE(back.count(), s.published);
  EXPECT_GT(out.count(), 800);
  EXPECT_GE(out.percentile_us(0.5), back.percentile_us(0.5) - LatencyHistogram::kBinUs);
  EXPECT_LT(back.percentile_us(0.5), 20000.0);  // within the histogram (memq answers within a tick or two)
  EXPECT_GT(box.force_lines(), 800);
  // the write itself: one non-blocking write per tick
  EXPECT_GT(s.device_write.count(), 900);
  std::printf("the device write itself: p50 %.0f / p99 %.0f / max %.0f us\n", s.device_write.percentile_us(0.5),
              s.device_write.percentile_us(0.99), s.device_write.max_us());
}

}  // namespace
}  // namespace pcisim::clients
