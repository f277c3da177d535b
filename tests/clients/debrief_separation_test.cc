// Issue #35 item 4: the scripted novice (scenes/trainees/novice.json) and the built-in trainee
// (the expert) played headless through the built-in scene's physics (its beating heart, moving
// tree, blood and wire), the debrief's figures recorded as the server records them: the wire state
// each step, the pedals, beam time and pulses at the scene's rates, each contrast press. The
// debrief must separate them on every figure that should separate them.
#include <gtest/gtest.h>

#include "anatomy/phantom/coronary_phantom.h"
#include "clients/bridge/trainee_script.h"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "physics/world.h"
#include "server/debrief/session_metrics.h"
#include "server/scene/scene.h"

namespace pcisim::server {
namespace {

constexpr int64_t kStartNs = 1'000'000'000;

DebriefFigures play(const clients::TraineeScript& script) {
  using I = pcisim_lcm::instrument_state_t;
  const Scene scene = default_scene();
  const anatomy::VesselTree tree =
      anatomy::make_coronary_phantom(anatomy::CoronaryPhantomSpec{scene.world.anatomy.seed});
  physics::World world(scene.world);
  const XraySpec& x = *scene.xray;
  const xray::CArmSpec& arm = x.fluoro.c_arm;
  SessionMetrics m;
  m.begin_pipeline(
      scene.debrief, tree, false,
      beam_geometry(arm.source_to_axis_mm, arm.source_to_image_mm, arm.width * arm.pixel_mm, arm.height * arm.pixel_mm),
      kStartNs);
  const double dt = scene.world.step_s;
  const int fluoro_every = static_cast<int>(std::lround(1.0 / (dt * x.pulse_rate_fps)));
  const int cine_every = static_cast<int>(std::lround(1.0 / (dt * x.cine_rate_fps)));
  physics::WorldSnapshot s;
  bool contrast_was = false;
  int64_t end_ns = kStartNs;
  for (int k = 0; k * dt <= script.duration_s() + 0.5; ++k) {
    const double t = k * dt;
    const clients::InstrumentReading r = script.sample(t);
    physics::InstrumentInput in;
    in.insertion_m = r.insertion_mm * 1e-3;
    in.rotation_rad = r.rotation_rad;
    in.insertion_rate_m_per_s = r.insertion_rate_mm_s * 1e-3;
    in.rotation_rate_rad_per_s = r.rotation_rate_rad_s;
    world.step(in);
    world.write_snapshot(s);
    end_ns = kStartNs + static_cast<int64_t>(t * 1e9);
    m.record_wire(s, x.initial_pose.primary_deg, x.initial_pose.secondary_deg, end_ns);
    const bool fluoro = (r.buttons & I::BUTTON_FLUORO_PEDAL) != 0, cine = (r.buttons & I::BUTTON_CINE_PEDAL) != 0;
    m.record_pedals(fluoro, cine, end_ns);
    if (fluoro || cine) {
      m.record_beam_time(dt, cine, x.initial_pose.primary_deg, x.initial_pose.secondary_deg);
      if (k % (cine ? cine_every : fluoro_every) == 0) m.record_pulse(cine);
    }
    const bool contrast = (r.buttons & I::BUTTON_CONTRAST) != 0;
    if (contrast && !contrast_was) m.record_injection(x.injection_volume_ml, end_ns);
    contrast_was = contrast;
  }
  return m.figures(end_ns);
}

TEST(DebriefSeparation, TheNoviceAndTheExpertAreToldApartOnEveryFigureThatShouldTellThem) {
  const DebriefFigures expert = play(clients::TraineeScript::parse(clients::TraineeScript::builtin_text(), "built-in"));
  const DebriefFigures novice = play(clients::TraineeScript::load(PCISIM_SOURCE_DIR "/scenes/trainees/novice.json"));
  const auto show = [](const DebriefFigures& f) { return to_json(f).dump(); };
  SCOPED_TRACE("expert " + show(expert));
  SCOPED_TRACE("novice " + show(novice));
  // Gallagher 2006: time, fluoroscopy and contrast; Rolls 2017: the tip's path; and what only a
  // simulator knows: the time off the route to the target
  EXPECT_GT(novice.procedure_time_s, 1.5 * expert.procedure_time_s);
  EXPECT_GT(novice.fluoro_time_s, 1.5 * expert.fluoro_time_s);
  EXPECT_GT(novice.air_kerma_mgy, 1.5 * expert.air_kerma_mgy);
  EXPECT_GT(novice.dap_gycm2, 1.5 * expert.dap_gycm2);
  EXPECT_GT(novice.cine_runs, expert.cine_runs);
  EXPECT_GT(novice.contrast_ml, expert.contrast_ml);
  EXPECT_GT(novice.tip_path_in_vessels_mm, 1.5 * expert.tip_path_in_vessels_mm);
  EXPECT_GT(novice.tip_path_mm, expert.tip_path_mm);
  EXPECT_GT(novice.wrong_branch_s, expert.wrong_branch_s + 3.0) << "the novice's detours into the LCx and D1";
  // both reach the LAD, the expert sooner
  ASSERT_GE(expert.target_reached_s, 0.0);
  ASSERT_GE(novice.target_reached_s, 0.0);
  EXPECT_GT(novice.target_reached_s, expert.target_reached_s);
}

}  // namespace
}  // namespace pcisim::server
