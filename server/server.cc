#include "server/server.h"

#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "physics/heart/heart_fit.h"
#include "server/case_builder.h"
#include "server/haptic_loop.h"
#include "server/lcm_io.h"
#include "server/physics_loop.h"
#include "realtime/clock.h"
#include "realtime/realtime_setup.h"
#include "server/ultrasound_loop.h"
#include "server/beat_samples.h"
#include "server/xray_loop.h"
#include "physics/soft_tissue/tissue_scene.h"

namespace pcisim::server {

struct Server::Impl {
  Scene scene;
  std::shared_ptr<const anatomy::Case> anatomy;  // built once; physics, x-ray and status share it
  lcm::LCM& lcm;
  lcm::LCM* images;
  SessionLimits own_limits;
  SessionLimits* limits;
  SessionMetrics own_metrics;
  SessionMetrics* metrics;
  SharedState state;
  std::unique_ptr<PhysicsLoop> physics;
  std::unique_ptr<XrayLoop> xray;              // only when the scene lists xray
  std::unique_ptr<UltrasoundLoop> ultrasound;  // only when the scene lists ultrasound
  int64_t start_ns = 0;
  std::atomic<bool> haptic_fifo{false};
  // status rates are over the last second, not since start
  int64_t last_status_ns = 0, last_haptic_ticks = 0, last_physics_steps = 0;
  // the next scene's server, built on `builder` while this one runs (set_successor_builder)
  SuccessorBuilder build_successor;
  std::thread builder;
  std::atomic<bool> successor_built{false};
  std::unique_ptr<Server> successor;  // the builder's, read after successor_built
  std::string successor_error;

  // (the session's limits take this scene's bounds when it starts running: a server built while
  // another runs must not change the running one's)
  Impl(const Scene& s, lcm::LCM& l, lcm::LCM* i, SessionLimits* lim, SessionMetrics* met)
      : scene(s), lcm(l), images(i), limits(lim ? lim : &own_limits), metrics(met ? met : &own_metrics) {}
  ~Impl() {
    if (builder.joinable()) builder.join();
  }

  // a scene asked for over LCM: its server built on the builder thread, below the loops' priority
  void start_successor(Scene next) {
    successor_built = false;
    successor_error.clear();
    try {
      builder = std::thread([this, next = std::move(next)]() mutable {
        ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 10);
        try {
          successor = build_successor(std::move(next));
        } catch (const std::exception& e) {
          successor_error = e.what();
        } catch (...) {
          successor_error = "an unknown error";
        }
        successor_built.store(true, std::memory_order_release);
      });
    } catch (const std::system_error& e) {
      limits->count_scene_rejected();
      spdlog::error("session: no thread to build the scene ({}); the running one goes on", e.what());
    }
  }

  // the main thread's watch over a reload: true once the successor is built and should take
  // over (a failed build is refused and this server runs on)
  bool successor_ready(const std::string& source) {
    if (!build_successor) return state.scene_requested.load();  // run() returns for the caller to rebuild
    if (!builder.joinable()) {
      if (!state.scene_requested.load()) return false;
      std::optional<Scene> next;
      {
        std::lock_guard lock(state.scene_mutex);
        next = std::move(state.requested_scene);
        state.requested_scene.reset();
        state.scene_requested = false;
      }
      if (next) {
        spdlog::info("session: building {} while {} runs", next->source, source);
        start_successor(std::move(*next));
      }
      return false;
    }
    if (!successor_built.load(std::memory_order_acquire)) return false;
    builder.join();
    if (successor) return true;
    limits->count_scene_rejected();
    spdlog::error("session: refused the scene: it cannot be built: {}; {} runs on", successor_error, source);
    return false;
  }

  // in place (the status's report keeps its storage: nothing allocated once warm)
  void fill_stats(double elapsed_s, StatsReport* out) {
    StatsReport& r = *out;
    collect_stats(state, *physics, elapsed_s, haptic_fifo, &r);
    r.effects = scene.effects;
    r.xray_frames = state.xray_frames.load();
    // the pulse rate: a C-arm move's extra frame is a refresh, not a pulse (the pulses read
    // first: a pulse counted after its beam time was read would overstate the rate)
    const auto pulses = static_cast<double>(state.xray_pulses.load());
    const double on_s = state.xray_on_ns.load() * 1e-9;
    r.xray_fps = on_s > 0 ? pulses / on_s : 0.0;
    r.xray_render_ms = percentiles(state.xray_render_ns, 1e-6);
    r.ultrasound_frames = state.ultrasound_frames.load();
    r.ultrasound_render_ms = percentiles(state.ultrasound_render_ns, 1e-6);
    r.contrast_injections = limits->injections();
    r.contrast_ml = limits->contrast_ml();
    r.resets_refused = limits->resets_refused();
    r.scene_loads_refused = limits->scene_loads_refused();
    r.scenes_rejected = limits->scenes_rejected();
    r.injections_refused = limits->injections_refused();
    r.carm_moves_coalesced = xray ? state.carm_requests.load() - state.carm_moves.load() : 0;
  }
  StatsReport stats(double elapsed_s) {
    StatsReport r;
    fill_stats(elapsed_s, &r);
    return r;
  }

  // the once-a-second status, into the send thread's message
  StatsReport status_report;
  void status(pcisim_lcm::sim_status_t* out) {
    const int64_t now = realtime::monotonic_ns();
    StatsReport& r = status_report;
    fill_stats((now - start_ns) * 1e-9, &r);
    const double window_s = (now - last_status_ns) * 1e-9;
    if (window_s > 0) {
      r.haptic_rate_hz = (r.haptic_ticks - last_haptic_ticks) / window_s;
      r.physics_rate_hz = (r.physics_steps - last_physics_steps) / window_s;
    }
    last_status_ns = now;
    last_haptic_ticks = r.haptic_ticks;
    last_physics_steps = r.physics_steps;
    pcisim_lcm::sim_status_t& m = *out;
    to_message(r, now / 1000, 0, state.paused, &m);
    // the session's cath-lab figures, so a client that joins late reports them whole
    m.fluoro_on = state.fluoro_pedal_console || state.instrument_pedal_down(state.fluoro_pedal_instrument, now) ? 1 : 0;
    m.cine_on = state.cine_console || state.instrument_pedal_down(state.cine_instrument, now) ? 1 : 0;
    m.fluoro_time_s = state.xray_on_ns.load() * 1e-9;
    // the pose the beam shows (with no x-ray, the last target)
    m.carm_primary_deg = xray ? state.carm_primary_deg.load() : state.carm_target_primary_deg.load();
    m.carm_secondary_deg = xray ? state.carm_secondary_deg.load() : state.carm_target_secondary_deg.load();
    // the session's figures and refusals, across scene reloads
    m.contrast_injections = static_cast<int32_t>(r.contrast_injections);
    m.contrast_ml = r.contrast_ml;
    m.resets_refused = r.resets_refused;
    m.scene_loads_refused = r.scene_loads_refused;
    m.scenes_rejected = r.scenes_rejected;
    m.injections_refused = r.injections_refused;
    m.carm_moves_coalesced = r.carm_moves_coalesced;
  }
};

void Server::fill_status(pcisim_lcm::sim_status_t* m) {
  impl_->status(m);
}

Server::Server(const Scene& scene, lcm::LCM& control, lcm::LCM* images, SessionLimits* limits, SessionMetrics* metrics)
    : impl_(std::make_unique<Impl>(scene, control, images, limits, metrics)) {
  spdlog::info("scene '{}' ({}): effects [{}], physics {} Hz", scene.name, scene.source,
               fmt::format("{}", fmt::join(scene.effects, ", ")), scene.physics_rate_hz);
  const int64_t t0 = realtime::monotonic_ns();
  impl_->anatomy = build_case(scene);
  const anatomy::Case& anatomy = *impl_->anatomy;
  spdlog::info("anatomy '{}' ({}): {} branches, lumen {} triangles, {} ({:.0f} ms)", anatomy.name,
               scene.case_dir.empty() ? std::string("procedural phantom") : "case " + scene.case_dir,
               anatomy.vessels.branches.size(), anatomy.lumen.triangles.size(),
               anatomy.ct ? fmt::format("CT {}x{}x{}", anatomy.ct->dims[0], anatomy.ct->dims[1], anatomy.ct->dims[2])
                          : std::string("no CT"),
               (realtime::monotonic_ns() - t0) * 1e-6);
  const int64_t t_world = realtime::monotonic_ns();
  impl_->physics = std::make_unique<PhysicsLoop>(scene, impl_->anatomy, impl_->state);
  spdlog::info("world built in {:.0f} ms", (realtime::monotonic_ns() - t_world) * 1e-6);
  if (anatomy.heart_vertices_m.cols() > 0)
    spdlog::info("heart: {}'s own, the template fitted to its CT ({} vertices)", anatomy.name,
                 anatomy.heart_vertices_m.cols());
  if (const auto& fit = impl_->physics->world().heart_fit(); fit.branches_lifted > 0)
    spdlog::info("heart fitted under {}: {} branch(es) lifted clear, epicardium dented up to {:.1f} mm", anatomy.name,
                 fit.branches_lifted, fit.max_dent_m * 1e3);
  // branch names for wire_state_t and the log: the case's tree, the one physics runs on
  std::vector<std::string> names;
  for (const auto& b : anatomy.vessels.branches) names.push_back(b.name);
  branch_namer = [names](int i) -> const std::string& {
    static const std::string unknown;
    return i >= 0 && i < static_cast<int>(names.size()) ? names[i] : unknown;
  };
  if (const auto* tissue = impl_->physics->world().tissue_state())
    spdlog::info("{}: {} particles in {} clusters (radius {:.1f} mm), {} tets for the image, {} fiducials; {}",
                 anatomy.organ->name, tissue->body().particle_count(), tissue->model().clusters.size(),
                 tissue->model().spec.particle_radius_m * 1e3, tissue->model().tets.size(),
                 tissue->model().fiducial_skin.size(), tissue->has_probe() ? "probe in contact" : "no probe");
  if (scene.ultrasound) {
    const auto* tissue = impl_->physics->world().tissue_state();
    if (!tissue) throw std::invalid_argument("ultrasound: needs soft_tissue");
    impl_->ultrasound = std::make_unique<UltrasoundLoop>(scene, anatomy, tissue->model().tet_vertices_m,
                                                         tissue->model().tets, impl_->state, images);
    spdlog::info("ultrasound ready ({}x{} px, {} mm deep, {} Hz, frames {})", scene.ultrasound->settings.width_px,
                 scene.ultrasound->settings.height_px, scene.ultrasound->settings.depth_mm,
                 scene.ultrasound->frame_rate_hz, images ? "published" : "not published");
  }
  if (scene.xray) {
    const int64_t t1 = realtime::monotonic_ns();
    // the background beats with the heart the tree rides (one cycle sampled now, warped per bin)
    std::optional<xray::BeatSamples> beat;
    if (scene.world.vessel_motion && scene.xray->heart_phase_bins > 0)
      beat = beat_samples_mm(impl_->physics->world().sample_beat_cycle(scene.xray->heart_phase_bins));
    impl_->xray = std::make_unique<XrayLoop>(scene, anatomy, impl_->state, images, beat ? &*beat : nullptr);
    spdlog::info("fluoroscopy ready in {:.0f} ms ({}x{} detector, {} fps, frames {}, background {})",
                 (realtime::monotonic_ns() - t1) * 1e-6, scene.xray->fluoro.c_arm.width,
                 scene.xray->fluoro.c_arm.height, scene.xray->pulse_rate_fps, images ? "published" : "not published",
                 beat ? fmt::format("beating, {} phase bins {}", scene.xray->heart_phase_bins,
                                    scene.xray->heart_phase_blend ? "blended" : "nearest")
                      : std::string("still"));
  }
}

Server::~Server() = default;

StatsReport Server::run(double duration_s, const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  m.limits->configure(m.scene.session);
  const bool locked = realtime::try_mlockall();
  const realtime::CpuLatencyRequest latency(cpu_latency_us);
  LcmIo io(
      m.lcm, m.state, *m.limits, m.scene.xray ? m.scene.xray->injection_volume_ml : 0.0,
      [this](pcisim_lcm::sim_status_t& s) { fill_status(&s); }, branch_namer,
      m.scene.world.probe_contact ? LcmIo::Instrument::kProbe : LcmIo::Instrument::kWire, m.metrics);

  m.start_ns = m.last_status_ns = realtime::monotonic_ns();
  // the debrief: this scene's thresholds and route; the rod computes the wall's force, the
  // chain-mail does not; the dose is reckoned at this C-arm's reference point
  {
    const auto& g = m.scene.world.guidewire;
    const bool forces = g && g->model == physics::GuidewireModel::kRod;
    BeamGeometry beam;
    int width = 0, height = 0;
    if (m.scene.xray) {
      const xray::CArmSpec& c = m.scene.xray->fluoro.c_arm;
      beam = beam_geometry(c.source_to_axis_mm, c.source_to_image_mm, c.width * c.pixel_mm, c.height * c.pixel_mm);
      width = c.width;
      height = c.height;
    }
    m.metrics->begin_pipeline(m.scene.debrief, m.anatomy->vessels, forces, beam, m.start_ns, width, height);
    if (m.xray) m.xray->set_metrics(m.metrics);
  }
  io.start();
  HapticLoopConfig haptic_config;
  haptic_config.params = m.scene.haptics;
  std::thread haptic([&] { m.haptic_fifo = run_haptic_loop(haptic_config, m.state); });
  std::thread physics([&] { m.physics->run(); });
  std::thread xray;
  if (m.xray) xray = std::thread([&] { m.xray->run(); });
  std::thread ultrasound;
  if (m.ultrasound) ultrasound = std::thread([&] { m.ultrasound->run(); });
  spdlog::info("running: haptic 1000 Hz, physics {} Hz{}{}{}", m.scene.physics_rate_hz, locked ? ", memory locked" : "",
               latency.granted() ? fmt::format(", CPU wake-up latency held at {} us", cpu_latency_us) : "",
               duration_s > 0 ? fmt::format(", for {} s", duration_s) : "");

  // the main thread only watches the clock and logs once a second
  int64_t next_log_ns = m.start_ns + 1'000'000'000;
  // 0, or anything past ~290 years (inf included), runs until stopped
  const int64_t end_ns =
      duration_s > 0 && duration_s < 9e9 ? m.start_ns + static_cast<int64_t>(duration_s * 1e9) : INT64_MAX;
  while (!stop.load() && !m.successor_ready(m.scene.source) && realtime::monotonic_ns() < end_ns) {
    realtime::sleep_until_ns(std::min(end_ns, realtime::monotonic_ns() + 20'000'000));
    if (m.state.debrief_requested.exchange(false)) {
      if (on_debrief_request) {
        on_debrief_request();
      } else {
        spdlog::warn("session: a debrief was asked for, but this server writes none (--debrief-json, --debrief-html)");
      }
    }
    if (realtime::monotonic_ns() >= next_log_ns) {
      next_log_ns += 1'000'000'000;
      const double t_s = (realtime::monotonic_ns() - m.start_ns) * 1e-9;
      if (m.scene.world.probe_contact) {
        spdlog::info(
            "t={:5.1f}s  probe depth {:6.1f} mm  force {:5.2f} N along the beam  ultrasound {} frames  haptic {} "
            "ticks",
            t_s, m.state.wire_insertion_mm.load(), m.state.probe_force_n.load(), m.state.ultrasound_frames.load(),
            m.state.haptic.iterations.load());
        continue;
      }
      const int branch = m.state.wire_tip_branch.load();
      spdlog::info("t={:5.1f}s  insertion {:6.1f} mm  rotation {:6.2f} rad  tip in {}  contacts {:3d}  haptic {} ticks",
                   t_s, m.state.wire_insertion_mm.load(), m.state.wire_rotation_rad.load(),
                   branch_namer && branch >= 0 ? std::string(branch_namer(branch)) : std::string("-"),
                   m.state.wire_contacts.load(), m.state.haptic.iterations.load());
    }
  }

  // stop the loops first, then the I/O, which sends the zero force command last
  // (the haptic loop last: the physics thread may sleep a period before it sees the stop, and the
  // force it feeds the hand stays fresh meanwhile)
  m.state.stop = true;
  physics.join();
  if (xray.joinable()) xray.join();
  if (ultrasound.joinable()) ultrasound.join();
  io.stop_receiving();
  m.state.stop_haptic = true;
  haptic.join();
  const double elapsed_s = (realtime::monotonic_ns() - m.start_ns) * 1e-9;
  io.stop();
  StatsReport r = m.stats(elapsed_s);
  r.cpu_latency_held = latency.granted();
  return r;
}

void Server::inject_physics_stall(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0 || seconds > 3600.0)
    throw std::invalid_argument("inject_physics_stall: seconds must be in [0, 3600]");
  impl_->state.inject_stall_us = static_cast<int64_t>(seconds * 1e6);
}

void Server::set_successor_builder(SuccessorBuilder build) {
  impl_->build_successor = std::move(build);
}

// the successor built while this server ran, with a scene asked for meanwhile passed on to it
bool Server::building_successor() const {
  return impl_->builder.joinable();
}

std::unique_ptr<Server> Server::take_successor() {
  Impl& m = *impl_;
  if (m.builder.joinable()) return nullptr;  // (still building: run() stopped for another reason)
  std::unique_ptr<Server> next = std::move(m.successor);
  if (next) {
    std::lock_guard lock(m.state.scene_mutex);
    if (m.state.requested_scene) {
      std::lock_guard next_lock(next->impl_->state.scene_mutex);
      next->impl_->state.requested_scene = std::move(m.state.requested_scene);
      next->impl_->state.scene_requested = true;
      m.state.requested_scene.reset();
      m.state.scene_requested = false;
    }
  }
  return next;
}

std::optional<Scene> Server::take_requested_scene() {
  std::lock_guard lock(impl_->state.scene_mutex);
  std::optional<Scene> scene = std::move(impl_->state.requested_scene);
  impl_->state.requested_scene.reset();
  return scene;
}

}  // namespace pcisim::server
