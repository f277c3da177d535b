#pragma once
// The instrument bridge loop: polls a device at 1 kHz on absolute deadlines, publishes
// instrument_state_t, and hands the device the force the server sends back (zero first in any
// fault: force_gate.h) every tick.
// A device in fault is published as STATUS_FAULT with its last good position: no motion.
// A probe bridge publishes a probe script's probe_state_t instead, on the same clock.
#include <array>
#include <atomic>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "clients/bridge/device_profile.h"
#include "clients/bridge/force_gate.h"
#include "clients/bridge/instrument_device.h"
#include "clients/bridge/latency_histogram.h"
#include "protocol/encoded_publisher.h"
#include "clients/bridge/probe_script.h"
#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/probe_state_t.hpp"

namespace pcisim::clients {

struct BridgeOptions {
  double rate_hz = 1000.0;
  double duration_s = 0.0;         // 0 = until stop (or a replay's end)
  double wait_for_server_s = 0.0;  // hold the device at t = 0 until the first force command
  int device_id = 1;               // of every message published
  bool log_each_second = true;
  // like the server's haptic loop: real-time priority for the publishing thread while it runs and
  // CPU wake-ups held at this latency (PM QoS; -1 = leave the CPUs alone); quiet when not permitted
  int fifo_priority = 60;
  int cpu_latency_us = 0;
  // the server's force on its way to the device: the instrument's scale, limits and filter
  // (device_profile.h); zero in any fault bypasses it
  ForceShaping force_shaping;
};

struct BridgeStats {
  int64_t published = 0, fault_samples = 0;
  // the force handed to the device: ticks it reached it, ticks it was zero because of a fault
  // (force_gate.h), and the last zeroing's reason
  int64_t force_rendered = 0, force_zeroed = 0;
  ForceGateState force_state = ForceGateState::kNoCommand;
  // end-to-end latency (issue #37): from an instrument sample leaving the bridge to the first
  // force command computed from it (its instrument_seq) arriving back, and on to the first device
  // write of that force
  LatencyHistogram sample_to_force, sample_to_device;
  LatencyHistogram device_write;  // the device's render() call itself, every tick
  int64_t missed_periods = 0;     // deadlines skipped because a sample came more than a period late
  int64_t forces_received = 0, forces_bad = 0;
  double elapsed_s = 0.0;  // from the first publish to the last (waiting for the server included)
  double last_force_n = 0.0, last_torque_nmm = 0.0;
};

class Bridge {
 public:
  // `lcm` and the device or probe script must outlive the bridge; the bridge runs its receive loop
  // on its own thread
  Bridge(lcm::LCM& lcm, InstrumentDevice& device, const BridgeOptions& options);
  // a probe bridge: probe_state_t on PCISIM_PROBE from the script, no instrument_state_t
  Bridge(lcm::LCM& lcm, const ProbeScript& probe, const BridgeOptions& options);
  BridgeStats run(const std::atomic<bool>& stop);

 private:
  // what one run keeps from tick to tick: the message, filled in place, and the device's fault state
  struct InstrumentTick {
    pcisim_lcm::instrument_state_t message{};
    InstrumentReading reading, last_good;
    bool was_fault = false;
    ForceGateState force_state = ForceGateState::kNoCommand;
  };
  Bridge(lcm::LCM& lcm, InstrumentDevice* device, const ProbeScript* probe, const BridgeOptions& options);
  void on_force(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  // one tick's message; `log`: the once-a-second line; `render`: hand the device its force
  void publish_instrument(double t_s, int64_t now_ns, int64_t seq, bool log, bool render, InstrumentTick& tick,
                          BridgeStats& stats);
  void publish_probe(double t_s, int64_t now_ns, int64_t seq, bool log, pcisim_lcm::probe_state_t& message);
  // lcm-cpp's publish(message) allocates the bytes, and the channel's std::string, every call
  template <class Message>
  void publish(const Message& message);

  lcm::LCM& lcm_;
  InstrumentDevice* device_;  // exactly one of the two
  const ProbeScript* probe_;
  BridgeOptions options_;
  const std::string channel_;  // PCISIM_PROBE for a probe bridge, else PCISIM_INSTRUMENT
  pcisim_lcm::force_command_t force_{};
  std::atomic<int64_t> forces_received_{0}, forces_bad_{0};
  std::atomic<double> last_force_n_{0}, last_torque_nmm_{0}, last_axial_stiffness_{0}, last_torsional_stiffness_{0};
  std::atomic<int32_t> last_flags_{0};
  std::atomic<int64_t> last_instrument_seq_{-1};
  std::atomic<int64_t> last_command_ns_{-1};  // monotonic, when the last good command arrived
  // the seven above are one command: written under an odd version, read until a version holds
  // even and unchanged (a seqlock), so a fault's flags never pair with the next command's force
  std::atomic<uint64_t> command_version_{0};
  ForceGateInput last_command() const;
  // when each recent sample left (slot seq % kSentSlots, tagged with its seq), the newest
  // instrument_seq a command answered, and the histograms (each written by one thread)
  static constexpr int kSentSlots = 4096;
  std::array<std::atomic<int64_t>, kSentSlots> sent_ns_{}, sent_seq_{};
  std::atomic<int64_t> answered_seq_{-1}, published_seq_{-1};
  int64_t rendered_seq_ = -1;  // publishing thread: the newest answered sample written to the device
  LatencyHistogram sample_to_force_, sample_to_device_, device_write_;
  ForceShaper shaper_;
  // one message encoded, its buffer sized at construction (both types are of fixed size)
  protocol::EncodedPublisher publisher_;
};

}  // namespace pcisim::clients
