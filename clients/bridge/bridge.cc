#include "clients/bridge/bridge.h"

#include <stdexcept>
#include <string>

#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <thread>

#include "pcisim_lcm/instrument_state_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/clock.h"
#include "realtime/deadline_schedule.h"
#include "realtime/realtime_setup.h"

namespace pcisim::clients {

using realtime::monotonic_ns;

Bridge::Bridge(lcm::LCM& lcm, InstrumentDevice& device, const BridgeOptions& options)
    : Bridge(lcm, &device, nullptr, options) {}

Bridge::Bridge(lcm::LCM& lcm, const ProbeScript& probe, const BridgeOptions& options)
    : Bridge(lcm, nullptr, &probe, options) {}

Bridge::Bridge(lcm::LCM& lcm, InstrumentDevice* device, const ProbeScript* probe, const BridgeOptions& options)
    : lcm_(lcm),
      device_(device),
      probe_(probe),
      options_(options),
      channel_(probe ? protocol::kProbeChannel : protocol::kInstrumentChannel),
      shaper_(options.force_shaping),
      publisher_(static_cast<size_t>(probe ? pcisim_lcm::probe_state_t{}.getEncodedSize()
                                           : pcisim_lcm::instrument_state_t{}.getEncodedSize())) {
  if (!(options.rate_hz >= 1.0 && options.rate_hz <= 1e4))
    throw std::invalid_argument("bridge: rate_hz must be in [1, 10000], got " + std::to_string(options.rate_hz));
  validate(options.force_shaping);
  for (auto& seq : sent_seq_) seq = -1;  // no sample has left yet
  lcm_.subscribe(protocol::kForceChannel, &Bridge::on_force, this);
}

ForceGateInput Bridge::last_command() const {
  ForceGateInput in;
  for (;;) {
    const uint64_t before = command_version_.load(std::memory_order_acquire);
    if (before & 1u) continue;  // being written
    in.last_command_ns = last_command_ns_.load();
    in.flags = last_flags_.load();
    in.axial_n = last_force_n_.load();
    in.torque_nmm = last_torque_nmm_.load();
    in.axial_stiffness_n_per_mm = last_axial_stiffness_.load();
    in.torsional_stiffness_nmm_per_rad = last_torsional_stiffness_.load();
    in.instrument_seq = last_instrument_seq_.load();
    if (command_version_.load(std::memory_order_acquire) == before) return in;
  }
}

void Bridge::on_force(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  if (!protocol::decode_checked(*rbuf, force_)) {
    ++forces_bad_;
    return;
  }
  ++forces_received_;
  const int64_t now_ns = monotonic_ns();
  command_version_.fetch_add(1, std::memory_order_acq_rel);  // odd: being written
  last_force_n_ = force_.axial_force_n;
  last_torque_nmm_ = force_.torque_nmm;
  last_axial_stiffness_ = force_.axial_stiffness_n_per_mm;
  last_torsional_stiffness_ = force_.torsional_stiffness_nmm_per_rad;
  last_instrument_seq_ = force_.instrument_seq;
  last_flags_ = force_.flags;
  last_command_ns_ = now_ns;
  command_version_.fetch_add(1, std::memory_order_acq_rel);
  // the first command that answers a sample this bridge sent: its round trip (a server still
  // answering an earlier bridge's numbers is not counted, nor does it move the mark)
  const int64_t answered = force_.instrument_seq;
  if (answered > answered_seq_.load() && answered <= published_seq_.load()) {
    const int slot = static_cast<int>(answered % kSentSlots);
    if (sent_seq_[slot].load() == answered) {
      sample_to_force_.add((now_ns - sent_ns_[slot].load()) * 1e-3);
      answered_seq_ = answered;
    }
  }
}

BridgeStats Bridge::run(const std::atomic<bool>& stop) {
  // real-time while publishing; the calling thread gets its old scheduling back at the end
  int old_policy = SCHED_OTHER;
  sched_param old_param{};
  pthread_getschedparam(pthread_self(), &old_policy, &old_param);
  if (options_.fifo_priority > 0) realtime::try_sched_fifo(options_.fifo_priority);
  const realtime::CpuLatencyRequest latency(options_.cpu_latency_us);
  std::atomic<bool> done{false};
  std::thread rx([&] {
    while (!done) lcm_.handleTimeout(20);
  });

  InstrumentTick instrument;
  instrument.message.device_id = options_.device_id;
  pcisim_lcm::probe_state_t probe{};
  probe.device_id = options_.device_id;
  BridgeStats stats;
  const auto period_ns = static_cast<int64_t>(1e9 / options_.rate_hz);
  int64_t start_ns = monotonic_ns();
  bool waiting = options_.wait_for_server_s > 0;
  realtime::DeadlineSchedule schedule(start_ns, period_ns);
  int64_t next_log_ns = start_ns + 1'000'000'000, first_publish_ns = 0, last_publish_ns = start_ns;
  for (int64_t seq = 0; !stop; ++seq) {
    const int64_t now_ns = monotonic_ns();
    if (waiting && (forces_received_ > 0 || (now_ns - start_ns) * 1e-9 > options_.wait_for_server_s)) {
      waiting = false;
      if (forces_received_ == 0)
        spdlog::warn("bridge: no answer from the server after {} s, starting anyway", options_.wait_for_server_s);
      start_ns = now_ns;  // the device's clock starts now
      next_log_ns = now_ns + 1'000'000'000;
    }
    const double t_s = waiting ? 0.0 : (now_ns - start_ns) * 1e-9;
    if ((options_.duration_s > 0 && t_s >= options_.duration_s) || (device_ && device_->finished(t_s))) break;

    const bool log = options_.log_each_second && !waiting && now_ns >= next_log_ns;
    if (log) next_log_ns += 1'000'000'000;
    if (probe_) {
      publish_probe(t_s, now_ns, seq, log, probe);
    } else {
      publish_instrument(t_s, now_ns, seq, log, !waiting, instrument, stats);
    }
    ++stats.published;
    if (!first_publish_ns) first_publish_ns = now_ns;
    last_publish_ns = now_ns;

    realtime::sleep_until_ns(schedule.deadline_ns());
    stats.missed_periods += schedule.complete(monotonic_ns());
  }
  done = true;
  rx.join();
  pthread_setschedparam(pthread_self(), old_policy, &old_param);
  stats.elapsed_s = first_publish_ns ? (last_publish_ns - first_publish_ns) * 1e-9 : 0.0;
  stats.forces_received = forces_received_;
  stats.forces_bad = forces_bad_;
  stats.last_force_n = last_force_n_;
  stats.last_torque_nmm = last_torque_nmm_;
  stats.sample_to_force = sample_to_force_;
  stats.sample_to_device = sample_to_device_;
  stats.device_write = device_write_;
  return stats;
}

template <class Message>
void Bridge::publish(const Message& message) {
  publisher_.publish(lcm_, channel_, message);
}

void Bridge::publish_instrument(double t_s, int64_t now_ns, int64_t seq, bool log, bool render, InstrumentTick& tick,
                                BridgeStats& stats) {
  // a device in fault reports no motion: the last good position, rates zero, status fault
  const bool ok = device_->read(t_s, tick.reading);
  if (ok) tick.last_good = tick.reading;
  if (!ok) {
    ++stats.fault_samples;
    tick.last_good.insertion_rate_mm_s = tick.last_good.rotation_rate_rad_s = 0;
  }
  if (ok != !tick.was_fault) spdlog::warn(ok ? "bridge: device back" : "bridge: device fault, publishing STATUS_FAULT");
  tick.was_fault = !ok;
  const InstrumentReading& r = ok ? tick.reading : tick.last_good;
  auto& m = tick.message;
  m.utime = now_ns / 1000;
  m.seq = seq;
  m.status = ok ? pcisim_lcm::instrument_state_t::STATUS_OK : pcisim_lcm::instrument_state_t::STATUS_FAULT;
  m.buttons = r.buttons;
  m.insertion_mm = r.insertion_mm;
  m.rotation_rad = r.rotation_rad;
  m.insertion_rate_mm_s = r.insertion_rate_mm_s;
  m.rotation_rate_rad_s = r.rotation_rate_rad_s;
  {
    const int slot = static_cast<int>(seq % kSentSlots);
    sent_seq_[slot] = -1;  // the slot is being reused: no answer matches it until it is whole
    sent_ns_[slot] = monotonic_ns();
    sent_seq_[slot] = seq;
    published_seq_ = seq;
  }
  publish(m);
  // the force back to the device: the server's while it is fresh and healthy, else zero; none
  // while waiting for the server (the first line marks the start: a box may hold its script till then)
  if (!render) return;
  ForceSetpoint force;
  ForceGateInput command = last_command();
  command.device_ok = ok;
  command.now_ns = now_ns;
  const ForceGateState state = gate_force(command, &force);
  force = shaper_.step(force, 1.0 / options_.rate_hz, state != ForceGateState::kRendering);
  const int64_t write_ns = monotonic_ns();
  const bool delivered = device_->render(force, seq);
  device_write_.add((monotonic_ns() - write_ns) * 1e-3);
  stats.force_rendered += delivered ? 1 : 0;
  // the first write of a force that answers a newer sample: sample -> device latency
  const int64_t answered = answered_seq_.load();
  if (delivered && state == ForceGateState::kRendering && answered > rendered_seq_) {
    const int slot = static_cast<int>(answered % kSentSlots);
    if (sent_seq_[slot].load() == answered) sample_to_device_.add((monotonic_ns() - sent_ns_[slot].load()) * 1e-3);
    rendered_seq_ = answered;
  }
  if (state != ForceGateState::kRendering) {
    ++stats.force_zeroed;
    stats.force_state = state;
  }
  if (state != tick.force_state && forces_received_ > 0) spdlog::info("bridge: {}", describe(state));
  tick.force_state = state;
  if (log)
    spdlog::info(
        "bridge: t={:5.1f}s insertion {:6.1f} mm rotation {:6.2f} rad buttons {:#x}{} | renders {:+.3f} N "
        "{:+.3f} N·mm ({} commands)",
        t_s, r.insertion_mm, r.rotation_rad, r.buttons, ok ? "" : " FAULT", last_force_n_.load(),
        last_torque_nmm_.load(), forces_received_.load());
}

void Bridge::publish_probe(double t_s, int64_t now_ns, int64_t seq, bool log, pcisim_lcm::probe_state_t& m) {
  // a script never faults: every tick is STATUS_OK
  const ProbeReading r = probe_->sample(t_s);
  m.utime = now_ns / 1000;
  m.seq = seq;
  m.status = pcisim_lcm::probe_state_t::STATUS_OK;
  m.buttons = r.buttons;
  for (int k = 0; k < 3; ++k) m.position_mm[k] = r.position_mm[k];
  for (int k = 0; k < 4; ++k) m.orientation_wxyz[k] = r.orientation_wxyz[k];
  m.depth_mm = r.depth_mm;
  m.gain_db = r.gain_db;
  publish(m);
  if (log)
    spdlog::info(
        "bridge: t={:5.1f}s probe at ({:6.1f}, {:6.1f}, {:6.1f}) mm, wxyz ({:+.3f}, {:+.3f}, {:+.3f}, {:+.3f}), "
        "depth {:.0f} mm, gain {:+.1f} dB, buttons {:#x}",
        t_s, r.position_mm[0], r.position_mm[1], r.position_mm[2], r.orientation_wxyz[0], r.orientation_wxyz[1],
        r.orientation_wxyz[2], r.orientation_wxyz[3], r.depth_mm, r.gain_db, r.buttons);
}

}  // namespace pcisim::clients
