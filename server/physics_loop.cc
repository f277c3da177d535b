#include "server/physics_loop.h"

#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <system_error>

#include "realtime/clock.h"
#include "realtime/deadline_schedule.h"

namespace pcisim::server {

PhysicsLoop::PhysicsLoop(const Scene& scene, std::shared_ptr<const anatomy::Case> anatomy, SharedState& state)
    : spec_(scene.world),
      case_(std::move(anatomy)),
      state_(state),
      rate_hz_(scene.physics_rate_hz),
      lumen_cache_(nullptr),  // (the first world builds its own field)
      world_(make_world()) {
  lumen_cache_ = world_->shared_lumen();
  for (const auto& cost : world_->effect_costs()) {
    effects_.push_back(std::make_unique<EffectStats>());
    effects_.back()->name = cost.name;
  }
}

PhysicsLoop::~PhysicsLoop() {
  if (builder_.joinable()) builder_.join();
}

std::unique_ptr<physics::World> PhysicsLoop::make_world() const {
  return std::make_unique<physics::World>(spec_, case_->vessels, lumen_cache_, case_->heart, case_->heart_vertices_m,
                                          case_->organ ? &*case_->organ : nullptr);
}

void PhysicsLoop::start_build() {
  built_ = false;
  try {
    builder_ = std::thread([this, retired = std::move(retired_)]() mutable {
      // below the loops: the build must not take the cores the running world steps on
      ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 10);
      retired.reset();  // the world the last reset replaced, freed here rather than between two steps
      try {
        next_ = make_world();
      } catch (const std::exception& e) {
        build_error_ = e.what();
      } catch (...) {
        build_error_ = "an unknown error";
      }
      built_.store(true, std::memory_order_release);
    });
  } catch (const std::system_error& e) {
    spdlog::error("physics: no thread to build the reset's world ({}); the running one goes on", e.what());
  }
}

void PhysicsLoop::swap_if_built() {
  if (!builder_.joinable() || !built_.load(std::memory_order_acquire)) return;
  builder_.join();
  if (next_) {
    world_.swap(next_);
    retired_ = std::move(next_);  // the old world: the next builder (or the loop's end) frees it
    // a reset asked for while this one was being built is this one
    state_.reset_requested.store(false);
  } else {
    spdlog::error("physics: the reset's world could not be built ({}); the running one goes on", build_error_);
  }
}

void PhysicsLoop::step_once(int64_t now_ns) {
  if (state_.instrument_for_physics.refresh()) instrument_ = state_.instrument_for_physics.read_slot();
  physics::InstrumentInput input;
  input.insertion_m = instrument_.sample.insertion_m;
  input.rotation_rad = instrument_.sample.rotation_rad;
  input.insertion_rate_m_per_s = instrument_.sample.insertion_rate_m_per_s;
  input.rotation_rate_rad_per_s = instrument_.sample.rotation_rate_rad_per_s;
  input.buttons = static_cast<uint32_t>(instrument_.buttons);
  input.probe_present = instrument_.probe_present;
  input.probe_position_m = instrument_.probe_position_m;
  input.probe_orientation_wxyz = instrument_.probe_orientation_wxyz;
  input.probe_depth_mm = instrument_.probe_depth_mm;
  input.probe_gain_db = instrument_.probe_gain_db;
  world_->step(input);
  if (const int64_t stall_us = state_.inject_stall_us.exchange(0)) realtime::sleep_until_ns(now_ns + stall_us * 1000);

  physics::WorldSnapshot& snap = state_.snapshot_for_tx.write_slot();
  world_->write_snapshot(snap);
  state_.wire_insertion_mm.store(snap.insertion_m * 1e3, std::memory_order_relaxed);
  state_.wire_rotation_rad.store(snap.rotation_rad, std::memory_order_relaxed);
  state_.wire_tip_branch.store(snap.tip_branch, std::memory_order_relaxed);
  int contacts = 0;
  for (uint8_t c : snap.wire_contact) contacts += c;
  state_.wire_contacts.store(contacts, std::memory_order_relaxed);
  state_.probe_force_n.store(-snap.probe_force_n.dot(snap.probe_rotation.col(2)), std::memory_order_relaxed);
  if (snap.probe_present) {
    state_.probe_beam_x.store(snap.probe_rotation(0, 2), std::memory_order_relaxed);
    state_.probe_beam_y.store(snap.probe_rotation(1, 2), std::memory_order_relaxed);
    state_.probe_beam_z.store(snap.probe_rotation(2, 2), std::memory_order_relaxed);
  }
  state_.snapshot_for_tx.publish();
  state_.sim_time_s.store(snap.time_s, std::memory_order_relaxed);
  if (state_.xray_enabled.load(std::memory_order_relaxed)) {
    state_.snapshot_for_xray.write_slot() = snap;  // same sizes every step: no allocation after the first
    state_.snapshot_for_xray.publish();
  }
  if (state_.ultrasound_enabled.load(std::memory_order_relaxed)) {
    state_.snapshot_for_ultrasound.write_slot() = snap;
    state_.snapshot_for_ultrasound.publish();
  }

  publish_model(now_ns);

  const auto costs = world_->effect_costs();
  for (size_t i = 0; i < costs.size() && i < effects_.size(); ++i)
    effects_[i]->step_ns.record(static_cast<int64_t>(costs[i].last_step_ms * 1e6));
}

// the model is stamped on the haptic thread's clock; two physics periods of validity. Before the
// world's first step its model is invalid (valid_for_us 0); where the world will feed the hand (a
// wire or a probe) it stands in as a zero force valid for two periods, so that a pipeline taking
// over after a reload answers at once instead of flagging stale until its first step is done
void PhysicsLoop::publish_model(int64_t now_ns) {
  physics::LocalForceModel model = world_->force_model();
  if (model.valid_for_us == 0 && world_->time_s() == 0.0 && (spec_.guidewire || spec_.soft_tissue))
    model.valid_for_us = static_cast<int64_t>(std::llround(2e6 / rate_hz_));
  model.made_utime = now_ns / 1000;
  state_.force_model.write_slot() = model;
  state_.force_model.publish();
}

void PhysicsLoop::run() {
  // the world as built, before its first step: the haptic loop has a fresh model at once (after a
  // reload this pipeline takes over from the last, and its first step may take a while)
  publish_model(realtime::monotonic_ns());
  const auto period_ns = static_cast<int64_t>(std::llround(1e9 / rate_hz_));
  realtime::DeadlineSchedule schedule(realtime::monotonic_ns(), period_ns);
  int64_t last_wake_ns = 0;
  while (!state_.stop.load(std::memory_order_relaxed)) {
    const int64_t deadline_ns = schedule.deadline_ns();
    realtime::sleep_until_ns(deadline_ns);
    const int64_t wake_ns = realtime::monotonic_ns();
    state_.physics.mark_wake(wake_ns);

    // a reset: the world built again on the builder thread while this one steps on, swapped in
    // between two steps (allocation is fine here, not inside step)
    swap_if_built();
    if (!builder_.joinable() && state_.reset_requested.exchange(false)) start_build();
    if (!state_.paused.load(std::memory_order_relaxed)) step_once(wake_ns);

    const int64_t done_ns = realtime::monotonic_ns();
    if (last_wake_ns > 0) state_.physics.period_ns.record(wake_ns - last_wake_ns);
    last_wake_ns = wake_ns;
    state_.physics.late_ns.record(wake_ns - deadline_ns);
    state_.physics.compute_ns.record(done_ns - wake_ns);
    state_.physics.iterations.fetch_add(1, std::memory_order_relaxed);
    if (const int64_t missed = schedule.complete(done_ns))
      state_.physics.overruns.fetch_add(missed, std::memory_order_relaxed);
  }
}

}  // namespace pcisim::server
