#include "server/stats.h"

#include <fmt/format.h>

namespace pcisim::server {

Percentiles percentiles(const realtime::LatencyHistogram& h, double scale) {
  return {h.quantile_ns(0.5) * scale, h.quantile_ns(0.99) * scale, h.quantile_ns(0.999) * scale, h.max_ns() * scale};
}

void collect_stats(const SharedState& state, const PhysicsLoop& physics, double elapsed_s, bool haptic_fifo,
                   StatsReport* out) {
  StatsReport& r = *out;
  r.elapsed_s = elapsed_s;
  r.haptic_ticks = state.haptic.iterations.load();
  r.haptic_rate_hz = state.haptic.rate_hz();
  r.haptic_period_us = percentiles(state.haptic.period_ns, 1e-3);
  r.haptic_compute_us = percentiles(state.haptic.compute_ns, 1e-3);
  r.haptic_late_us = percentiles(state.haptic.late_ns, 1e-3);
  r.haptic_overruns = state.haptic.overruns.load();
  r.forces_dropped = state.forces_dropped.load();
  r.haptic_fifo = haptic_fifo;
  r.physics_steps = state.physics.iterations.load();
  r.physics_rate_hz = state.physics.rate_hz();
  r.physics_target_hz = physics.rate_hz();
  r.physics_step_ms = percentiles(state.physics.compute_ns, 1e-6);
  r.physics_period_ms = percentiles(state.physics.period_ns, 1e-6);
  r.physics_overruns = state.physics.overruns.load();
  const auto& effects = physics.effects();
  r.effect_step_ms_p50.resize(effects.size());
  for (size_t i = 0; i < effects.size(); ++i) {
    r.effect_step_ms_p50[i].first = effects[i]->name;  // (the same name again: its storage kept)
    r.effect_step_ms_p50[i].second = effects[i]->step_ns.quantile_ns(0.5) * 1e-6;
  }
  r.lcm_rx = state.lcm_rx.load();
  r.lcm_tx = state.lcm_tx.load();
  r.lcm_dropped_bad = state.lcm_dropped_bad.load();
}

nlohmann::json to_json(const StatsReport& r) {
  auto pct = [](const Percentiles& p, bool with_p999) {
    nlohmann::json j = {{"p50", p.p50}, {"p99", p.p99}, {"max", p.max}};
    if (with_p999) j["p999"] = p.p999;
    return j;
  };
  nlohmann::json effects = nlohmann::json::object();
  for (const auto& [name, ms] : r.effect_step_ms_p50) effects[name] = {{"step_ms_p50", ms}};
  return {
      {"elapsed_s", r.elapsed_s},
      {"haptic",
       {{"rate_hz", r.haptic_rate_hz},
        {"ticks", r.haptic_ticks},
        {"period_us", pct(r.haptic_period_us, true)},
        {"compute_us", pct(r.haptic_compute_us, false)},
        {"wake_late_us", pct(r.haptic_late_us, true)},
        {"overruns", r.haptic_overruns},
        {"forces_dropped", r.forces_dropped},
        {"sched_fifo", r.haptic_fifo},
        {"cpu_latency_held", r.cpu_latency_held}}},
      {"physics",
       {{"rate_hz", r.physics_rate_hz},
        {"target_hz", r.physics_target_hz},
        {"steps", r.physics_steps},
        {"step_ms", pct(r.physics_step_ms, false)},
        {"period_ms", pct(r.physics_period_ms, false)},
        {"overruns", r.physics_overruns},
        {"effects", effects}}},
      {"effects", r.effects},
      {"xray", {{"frames", r.xray_frames}, {"fps", r.xray_fps}, {"render_ms", pct(r.xray_render_ms, false)}}},
      {"ultrasound", {{"frames", r.ultrasound_frames}, {"render_ms", pct(r.ultrasound_render_ms, false)}}},
      {"lcm", {{"rx", r.lcm_rx}, {"tx", r.lcm_tx}, {"dropped_bad", r.lcm_dropped_bad}}},
      {"session",
       {{"contrast_injections", r.contrast_injections},
        {"contrast_ml", r.contrast_ml},
        {"resets_refused", r.resets_refused},
        {"scene_loads_refused", r.scene_loads_refused},
        {"scenes_rejected", r.scenes_rejected},
        {"injections_refused", r.injections_refused},
        {"carm_moves_coalesced", r.carm_moves_coalesced}}},
  };
}

void to_message(const StatsReport& r, int64_t utime, int64_t seq, bool paused, pcisim_lcm::sim_status_t* out) {
  pcisim_lcm::sim_status_t& m = *out;
  m.utime = utime;
  m.seq = seq;
  m.haptic_rate_hz = r.haptic_rate_hz;
  m.haptic_period_us_p50 = r.haptic_period_us.p50;
  m.haptic_period_us_p99 = r.haptic_period_us.p99;
  m.haptic_period_us_p999 = r.haptic_period_us.p999;
  m.haptic_period_us_max = r.haptic_period_us.max;
  m.haptic_compute_us_p50 = r.haptic_compute_us.p50;
  m.haptic_compute_us_p99 = r.haptic_compute_us.p99;
  m.haptic_compute_us_max = r.haptic_compute_us.max;
  m.haptic_overruns = r.haptic_overruns;
  m.physics_rate_hz = r.physics_rate_hz;
  m.physics_step_ms_p50 = r.physics_step_ms.p50;
  m.physics_step_ms_p99 = r.physics_step_ms.p99;
  m.physics_step_ms_max = r.physics_step_ms.max;
  m.physics_overruns = r.physics_overruns;
  const size_t n = r.effect_step_ms_p50.size();
  m.num_effects = static_cast<int32_t>(n);
  m.effect_name.resize(n);
  m.effect_step_ms_p50.resize(n);
  for (size_t i = 0; i < n; ++i) {
    m.effect_name[i] = r.effect_step_ms_p50[i].first;
    m.effect_step_ms_p50[i] = r.effect_step_ms_p50[i].second;
  }
  m.xray_frames = r.xray_frames;
  m.xray_fps = r.xray_fps;
  m.lcm_rx = r.lcm_rx;
  m.lcm_tx = r.lcm_tx;
  m.lcm_dropped_bad = r.lcm_dropped_bad;
  m.paused = paused ? 1 : 0;
}

std::string human_summary(const StatsReport& r) {
  std::string effects;
  for (const auto& [name, ms] : r.effect_step_ms_p50) effects += fmt::format(" {} {:.3f} ms", name, ms);
  return fmt::format(
      "ran {:.1f} s\n"
      "  haptic  {:.1f} Hz ({})  period p50 {:.0f} / p99 {:.0f} / p99.9 {:.0f} / max {:.0f} us  "
      "compute p99 {:.1f} us  overruns {}\n"
      "  physics {:.1f} Hz of {:.0f}  step p50 {:.2f} / p99 {:.2f} / max {:.2f} ms  overruns {}\n"
      "  effects (p50):{}\n"
      "  x-ray   {} frames, {:.1f} fps while the pedal was down, render p50 {:.1f} / p99 {:.1f} ms\n"
      "  ultrasound {} frames, render p50 {:.1f} / p99 {:.1f} ms\n"
      "  lcm     rx {}  tx {}  dropped (bad) {}\n"
      "  session contrast {} injections, {:.1f} ml; refused: {} resets, {} scene loads, {} scenes, {} injections; "
      "{} C-arm targets coalesced",
      r.elapsed_s, r.haptic_rate_hz, r.haptic_fifo ? "SCHED_FIFO" : "SCHED_OTHER", r.haptic_period_us.p50,
      r.haptic_period_us.p99, r.haptic_period_us.p999, r.haptic_period_us.max, r.haptic_compute_us.p99,
      r.haptic_overruns, r.physics_rate_hz, r.physics_target_hz, r.physics_step_ms.p50, r.physics_step_ms.p99,
      r.physics_step_ms.max, r.physics_overruns, effects.empty() ? " none" : effects, r.xray_frames, r.xray_fps,
      r.xray_render_ms.p50, r.xray_render_ms.p99, r.ultrasound_frames, r.ultrasound_render_ms.p50,
      r.ultrasound_render_ms.p99, r.lcm_rx, r.lcm_tx, r.lcm_dropped_bad, r.contrast_injections, r.contrast_ml,
      r.resets_refused, r.scene_loads_refused, r.scenes_rejected, r.injections_refused, r.carm_moves_coalesced);
}

}  // namespace pcisim::server
