#include "server/haptic_loop.h"

#include "haptics/force_evaluator.h"
#include "realtime/clock.h"
#include "realtime/deadline_schedule.h"
#include "realtime/realtime_setup.h"

namespace pcisim::server {

bool run_haptic_loop(const HapticLoopConfig& config, SharedState& state) {
  const bool fifo = realtime::try_sched_fifo(config.fifo_priority);
  haptics::ForceEvaluator evaluator(config.params);
  InstrumentSlot instrument;
  ForceSlot out;

  realtime::DeadlineSchedule schedule(realtime::monotonic_ns(), config.period_ns);
  int64_t last_wake_ns = 0;
  while (!state.stop_haptic.load(std::memory_order_relaxed)) {
    const int64_t deadline_ns = schedule.deadline_ns();
    realtime::sleep_until_ns(deadline_ns);
    const int64_t wake_ns = realtime::monotonic_ns();
    const int64_t now_us = wake_ns / 1000;
    state.haptic.mark_wake(wake_ns);

    if (state.instrument_for_haptics.refresh()) instrument = state.instrument_for_haptics.read_slot();
    if (state.force_model.refresh()) evaluator.set_model(state.force_model.read_slot(), now_us);
    out.force = evaluator.tick(instrument.sample, now_us);
    out.utime = now_us;
    out.instrument_seq = instrument.seq;
    out.tick = state.haptic.iterations.fetch_add(1, std::memory_order_relaxed);
    if (!state.forces.push(out)) state.forces_dropped.fetch_add(1, std::memory_order_relaxed);

    // timing: lateness, period, compute; skip ahead rather than burst to catch up
    const int64_t done_ns = realtime::monotonic_ns();
    if (last_wake_ns > 0) state.haptic.period_ns.record(wake_ns - last_wake_ns);
    last_wake_ns = wake_ns;
    state.haptic.late_ns.record(wake_ns - deadline_ns);
    state.haptic.compute_ns.record(done_ns - wake_ns);
    if (const int64_t missed = schedule.complete(done_ns))
      state.haptic.overruns.fetch_add(missed, std::memory_order_relaxed);
  }
  return fifo;
}

}  // namespace pcisim::server
