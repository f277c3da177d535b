#include "physics/guidewire/wire_presets.h"
#include "server/scene/scene.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "json/json_reader.h"

namespace pcisim::server {
namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// the message of the json::JsonError a scene text raises, or "" when it parses
std::string error_of(const std::string& text) {
  try {
    parse_scene(text, "test.json");
  } catch (const json::JsonError& e) {
    return e.what();
  }
  return "";
}

TEST(Scene, BuiltInSceneIsTheRepositoryFileAndListsItsEffects) {
  EXPECT_EQ(default_scene_text(), read_file(PCISIM_SOURCE_DIR "/scenes/default.json"));
  const Scene s = default_scene();
  EXPECT_EQ(s.name, "default");
  EXPECT_EQ(s.source, "built-in");
  EXPECT_DOUBLE_EQ(s.physics_rate_hz, 30.0);
  EXPECT_EQ(s.effects, (std::vector<std::string>{"heart_beat", "vessel_motion", "guidewire", "blood_flow",
                                                 "vessel_contact", "friction", "xray", "contrast", "detector_noise"}));
  ASSERT_TRUE(s.xray.has_value());
  EXPECT_TRUE(s.xray->contrast);
  EXPECT_EQ(s.xray->fluoro.c_arm.width, 512);
  EXPECT_DOUBLE_EQ(s.xray->fluoro.photons_per_pixel, 2000.0);
  EXPECT_DOUBLE_EQ(s.xray->initial_pose.primary_deg, -30.0);
  ASSERT_TRUE(s.world.guidewire.has_value());
  EXPECT_EQ(s.world.guidewire->segment_count, 200);
  EXPECT_DOUBLE_EQ(s.world.guidewire->length_m, 0.300);
  ASSERT_TRUE(s.world.vessel_contact.has_value());
  EXPECT_DOUBLE_EQ(s.world.vessel_contact->sdf_spacing_m, 0.2e-3);
}

TEST(Scene, TheRodSceneIsTheDefaultWithTheRodWire) {
  const Scene s = load_scene_file(PCISIM_SOURCE_DIR "/scenes/rod.json");
  const Scene d = parse_scene(default_scene_text(), "default");
  EXPECT_EQ(s.effects, d.effects);
  ASSERT_TRUE(s.world.guidewire.has_value());
  EXPECT_EQ(s.world.guidewire->model, physics::GuidewireModel::kRod);
  EXPECT_EQ(s.world.guidewire->segment_count, 300);
  EXPECT_EQ(s.world.guidewire->rod_substeps, 8);
}

TEST(Scene, MinimalSceneBuildsOnlyTheWire) {
  const Scene s = load_scene_file(PCISIM_SOURCE_DIR "/scenes/minimal.json");
  EXPECT_EQ(s.effects, std::vector<std::string>{"guidewire"});
  EXPECT_TRUE(s.world.guidewire.has_value());
  EXPECT_FALSE(s.world.vessel_contact.has_value());
  EXPECT_FALSE(s.world.friction.has_value());
  EXPECT_FALSE(s.world.blood_flow.has_value());
}

TEST(Scene, CommentsAreAllowedAndUnitsConvert) {
  const Scene s = parse_scene(R"({ // a comment
      "physics_rate_hz": 60, /* another */
      "effects": {"guidewire": {"length_mm": 150, "segments": 50}}})",
                              "t");
  EXPECT_DOUBLE_EQ(s.world.step_s, 1.0 / 60.0);
  EXPECT_DOUBLE_EQ(s.world.guidewire->length_m, 0.150);
  EXPECT_EQ(s.world.guidewire->segment_count, 50);
}

TEST(Scene, TheGuidewireModelIsChosenByTheScene) {
  EXPECT_EQ(parse_scene(R"({"effects": {"guidewire": {}}})", "t").world.guidewire->model,
            physics::GuidewireModel::kChainMail);
  const Scene s = parse_scene(
      R"({"effects": {"guidewire": {"model": "rod", "bending_stiffness_nm2": 2e-5, "outer_diameter_mm": 0.3,
          "rod_substeps": 6}}})",
      "t");
  EXPECT_EQ(s.world.guidewire->model, physics::GuidewireModel::kRod);
  EXPECT_DOUBLE_EQ(s.world.guidewire->bending_stiffness_nm2, 2e-5);
  EXPECT_DOUBLE_EQ(s.world.guidewire->outer_diameter_m, 0.3e-3);
  EXPECT_EQ(s.world.guidewire->rod_substeps, 6);
  // a preset sets the section; a key beside it still wins
  const Scene stiff = parse_scene(
      R"({"effects": {"guidewire": {"model": "rod", "preset": "stiff_tip", "bending_stiffness_nm2": 3e-5}}})", "t");
  EXPECT_NEAR(stiff.world.guidewire->tip_bending_stiffness_nm2, physics::tip_stiffness_from_load_nm2(6.0, 0.010),
              1e-20);
  EXPECT_DOUBLE_EQ(stiff.world.guidewire->bending_stiffness_nm2, 3e-5);
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {"preset": "bmw"}}})"),
            "test.json: effects.guidewire.preset: expected one of \"none\", \"workhorse\", \"hydrophilic\", "
            "\"support\", \"stiff_tip\", got \"bmw\"");
  // the beat: the rod is pushed by the moving wall unless told otherwise, the chain-mail rides it
  EXPECT_EQ(s.world.guidewire->beat_coupling, physics::BeatCoupling::kContact);
  EXPECT_EQ(parse_scene(R"({"effects": {"guidewire": {}}})", "t").world.guidewire->beat_coupling,
            physics::BeatCoupling::kKinematic);
  EXPECT_EQ(parse_scene(R"({"effects": {"guidewire": {"model": "rod", "beat_coupling": "kinematic"}}})", "t")
                .world.guidewire->beat_coupling,
            physics::BeatCoupling::kKinematic);
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {"beat_coupling": "contact"}}})"),
            "test.json: effects.guidewire.beat_coupling: \"contact\" needs guidewire.model \"rod\" (the chain-mail "
            "rides the vessels: \"kinematic\")");
  // the rod's wall after its solve unless told to go inside it; the chain-mail has no such solve
  EXPECT_EQ(s.world.guidewire->rod_contact, physics::RodContactScheme::kProjection);
  EXPECT_EQ(parse_scene(R"({"effects": {"guidewire": {"model": "rod", "rod_contact": "solve"}}})", "t")
                .world.guidewire->rod_contact,
            physics::RodContactScheme::kSolve);
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {"rod_contact": "solve"}}})"),
            "test.json: effects.guidewire.rod_contact: \"solve\" needs guidewire.model \"rod\" (the chain-mail has no "
            "solve for the wall to enter)");
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {"model": "rod", "rod_contact": "implicit"}}})"),
            "test.json: effects.guidewire.rod_contact: expected one of \"projection\", \"solve\", got \"implicit\"");
  // the chain-mail's limits as set or from the section
  EXPECT_EQ(parse_scene(R"({"effects": {"guidewire": {"chain_mail_limits": "nitinol_core"}}})", "t")
                .world.guidewire->chain_mail_limits,
            physics::ChainMailLimits::kNitinolCore);
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {"chain_mail_limits": "wood"}}})"),
            "test.json: effects.guidewire.chain_mail_limits: expected one of \"given\", \"nitinol_core\", "
            "\"steel_core\", got \"wood\"");
}

TEST(Scene, EachBadInputNamesItsJsonPathAndWhatWasExpected) {
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {"segmnts": 10}}})"),
            "test.json: effects.guidewire.segmnts: unknown key (this object accepts: axial_damping_n_s_per_m, "
            "axial_stiffness_n_per_m, beat_coupling, bending_stiffness_nm2, body_alpha_max, body_alpha_min, "
            "body_beta_deg_per_mm, "
            "chain_mail_limits, feed_refuse_force_n, internal_force, length_mm, mass_per_length_kg_per_m, model, "
            "optimisation_passes, "
            "outer_diameter_mm, preset, rod_contact, rod_damping_per_s, rod_iterations, rod_substeps, segments, "
            "tip_alpha_max, "
            "tip_alpha_min, tip_angle_deg, tip_bending_stiffness_nm2, tip_beta_deg_per_mm, tip_length_mm, "
            "torsion_damping_nm_s_per_rad, torsional_rigidity_nm2)");
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {"model": "spring"}}})"),
            "test.json: effects.guidewire.model: expected one of \"chain_mail\", \"rod\", got \"spring\"");
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {"segments": "many"}}})"),
            "test.json: effects.guidewire.segments: expected an integer in [4, 4000], got \"many\"");
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {"segments": 2}}})"),
            "test.json: effects.guidewire.segments: expected an integer in [4, 4000], got 2");
  EXPECT_EQ(error_of(R"({"physics_rate_hz": -3, "effects": {}})"),
            "test.json: physics_rate_hz: expected a number in [1, 1000], got -3");
  EXPECT_EQ(error_of(R"({"effects": {"vessel_contact": {"sdf_spacing_mm": 5}, "guidewire": {}}})"),
            "test.json: effects.vessel_contact.sdf_spacing_mm: expected a number in [0.05, 2], got 5");
  EXPECT_EQ(error_of(R"({"effects": {"teleport": {}}})"),
            "test.json: effects.teleport: unknown effect (known: heart_beat, vessel_motion, guidewire, blood_flow, "
            "vessel_contact, friction, xray, contrast, detector_noise, soft_tissue, probe_contact, ultrasound)");
  EXPECT_EQ(error_of(R"({"effects": {"vessel_motion": {}}})"),
            "test.json: effects.vessel_motion: needs effect \"heart_beat\" in the same scene");
  EXPECT_EQ(error_of(R"({"effects": {"heart_beat": {"rate_bpm": 400}}})"),
            "test.json: effects.heart_beat.rate_bpm: expected a number in [20, 250], got 400");
  EXPECT_EQ(
      error_of(R"({"effects": {"guidewire": {}, "xray": {"pulse_rate_fps": 15, "cine_rate_fps": 25}}})"),
      "test.json: effects.xray.cine_rate_fps: expected a whole multiple or divisor of pulse_rate_fps (15), got 25");
  EXPECT_EQ(error_of(R"({"effects": {"heart_beat": {"cluster_size_mm": 0.01}}})"),
            "test.json: effects.heart_beat.cluster_size_mm: expected 0 (the global cluster only) or a number in [5, "
            "200], got 0.01");
  EXPECT_EQ(error_of(R"({"effects": {"heart_beat": {"solver": "magic"}}})").substr(0, 42),
            "test.json: effects.heart_beat.solver: expe");
  EXPECT_EQ(error_of(R"({"effects": {"heart_beat": {"motion_file": "no/such.motion"}}})"),
            "test.json: effects.heart_beat.motion_file: expected a heart motion file (docs/heart.md), cannot read "
            "\"no/such.motion\"");
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {}, "blood_flow": {"pulsatility": 2}}})"),
            "test.json: effects.blood_flow.pulsatility: expected a number in [0, 1], got 2");
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {}, "contrast": {}}})"),
            "test.json: effects.contrast: needs effect \"xray\" in the same scene");
  EXPECT_EQ(error_of(R"({"effects": {"xray": {"pulse_rate_fps": 20}}})"),
            "test.json: effects.xray.pulse_rate_fps: expected 7.5, 15 or 30, got 20");
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {}, "friction": {}}})"),
            "test.json: effects.friction: needs effect \"vessel_contact\" in the same scene");
  EXPECT_EQ(
      error_of(
          R"({"effects": {"guidewire": {}, "vessel_contact": {}, "friction": {"tip_static": 0.1, "tip_kinetic": 0.3}}})"),
      "test.json: effects.friction.tip_kinetic: expected at most tip_static");
  EXPECT_EQ(error_of(R"({"name": "x"})"), "test.json: effects: expected an object listing the effects to simulate");
  EXPECT_EQ(error_of(R"({"effects": [1, 2]})"), "test.json: effects: expected an object");
  EXPECT_EQ(error_of(R"({"effects": {}, "colour": "red"})"),
            "test.json: colour: unknown key (this object accepts: anatomy, debrief, effects, haptics, name, "
            "physics_rate_hz, session)");
  EXPECT_EQ(error_of(R"({"effects": {}, "debrief": {"tip_force_risk_n": 0}})"),
            "test.json: debrief.tip_force_risk_n: expected a number in [0.001, 10], got 0");
  EXPECT_EQ(error_of(R"({"haptics": {"interpolation": "cubic"}, "effects": {}})"),
            "test.json: haptics.interpolation: expected one of \"local_model\", \"zero_order_hold\", "
            "\"linear_extrapolation\", got \"cubic\"");
  EXPECT_EQ(error_of(R"({"haptics": {"peak_force_n": 1e9}, "effects": {}})"),
            "test.json: haptics.peak_force_n: expected a number in [0, 20], got 1000000000.0");
  EXPECT_NE(error_of(R"({"effects": {)").find("test.json: effects: not valid JSON"), std::string::npos);
}

// the anatomy is a phantom seed or a case folder, found beside the scene file
TEST(Scene, AnatomyIsASeedOrACaseFolderBesideTheScene) {
  const std::string effects = R"(, "effects": {"guidewire": {}}})";
  EXPECT_EQ(parse_scene(R"({"anatomy": {"case": "cases/p7"})" + effects, "/data/scenes/s.json").case_dir,
            "/data/scenes/cases/p7");
  EXPECT_EQ(parse_scene(R"({"anatomy": {"case": "/abs/p7"})" + effects, "/data/scenes/s.json").case_dir, "/abs/p7");
  EXPECT_EQ(parse_scene(R"({"anatomy": {"phantom_seed": 3})" + effects, "/data/s.json").case_dir, "");
  EXPECT_EQ(error_of(R"({"anatomy": {"case": "p7", "phantom_seed": 3})" + effects),
            "test.json: anatomy.case: give either a case folder or a phantom_seed, not both");
  EXPECT_EQ(error_of(R"({"anatomy": {"case": ""})" + effects),
            "test.json: anatomy.case: expected the path of a case folder");
}

TEST(Scene, MissingFileIsAClearError) {
  try {
    load_scene_file("/nonexistent/scene.json");
    FAIL() << "expected json::JsonError";
  } catch (const json::JsonError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/scene.json: cannot open the scene file: No such file or directory");
  }
}

TEST(Scene, WrittenSceneLoadsBackIdentically) {
  const auto path = std::filesystem::temp_directory_path() / "pcisim_scene_roundtrip.json";
  std::ofstream(path) << default_scene_text();
  const Scene a = load_scene_file(path.string()), b = default_scene();
  EXPECT_EQ(a.effects, b.effects);
  EXPECT_EQ(a.world.guidewire->segment_count, b.world.guidewire->segment_count);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace pcisim::server

namespace pcisim::server {
namespace {

TEST(Scene, SessionBoundsAreReadAndChecked) {
  const Scene s =
      parse_scene(R"({"effects": {}, "session": {"max_injections_per_min": 3, "max_contrast_ml": 90}})", "t.json");
  EXPECT_EQ(s.session.max_injections_per_min, 3);
  EXPECT_DOUBLE_EQ(s.session.max_contrast_ml, 90.0);
  EXPECT_DOUBLE_EQ(s.session.min_reset_interval_s, SessionLimitParams{}.min_reset_interval_s);
  EXPECT_EQ(error_of(R"({"effects": {}, "session": {"max_injections_per_min": 0}})"),
            "test.json: session.max_injections_per_min: expected an integer in [1, 60], got 0");
}

// nesting 100 000 deep overflowed the stack (in the error message's dump); a duplicate key hid a
// bad value (the last one won); 1e400 named neither the file nor the path
TEST(Scene, DeepNestingDuplicateKeysAndHugeNumbersAreRefusedNamingThePath) {
  const std::string deep = "{\"effects\": {}, \"name\": " + std::string(100000, '[') + std::string(100000, ']') + "}";
  EXPECT_EQ(error_of(deep),
            "test.json: name[][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][][]"
            "[][][][][][][][][][][][][][][][][][][][]: nested deeper than 64 levels");
  EXPECT_EQ(error_of(R"({"effects": {"guidewire": {"segments": 80, "segments": 100000}}})"),
            "test.json: effects.guidewire.segments: the key appears twice in one object");
  const std::string huge = error_of(R"({"effects": {"guidewire": {"segments": 1e400}}})");
  EXPECT_EQ(huge.rfind("test.json: effects.guidewire.segments: not valid JSON", 0), 0u) << huge;
}

// a step of 0.05 voxel turned a 0.5 s run into 22 s
TEST(Scene, AFluoroscopyStepFinerThanAQuarterVoxelIsRefused) {
  EXPECT_EQ(error_of(R"({"effects": {"xray": {"step_voxels": 0.05}}})"),
            "test.json: effects.xray.step_voxels: expected a number in [0.25, 4], got 0.05");
}

// the background's sampling: one sample per voxel plane by default; a scene that gives a step
// asks for trilinear steps; both at once is refused naming the key
TEST(Scene, TheFluoroscopySamplesVoxelPlanesUnlessAStepIsAskedFor) {
  const auto projector_of = [](const char* text) { return parse_scene(text, "test.json").xray->fluoro.projector; };
  const auto planes = projector_of(R"({"effects": {"xray": {}}})");
  EXPECT_TRUE(planes.trilinear.slices);
  const auto steps = projector_of(R"({"effects": {"xray": {"step_voxels": 0.5}}})");
  EXPECT_FALSE(steps.trilinear.slices);
  EXPECT_EQ(steps.trilinear.step_voxels, 0.5);
  EXPECT_FALSE(projector_of(R"({"effects": {"xray": {"sampling": "steps"}}})").trilinear.slices);
  EXPECT_EQ(error_of(R"({"effects": {"xray": {"sampling": "planes", "step_voxels": 2}}})"),
            "test.json: effects.xray.step_voxels: no step_voxels with sampling \"planes\" (one sample per voxel "
            "plane); use sampling \"steps\"");
  EXPECT_EQ(error_of(R"({"effects": {"xray": {"sampling": "rays"}}})").rfind("test.json: effects.xray.sampling", 0),
            0u);
  EXPECT_FALSE(projector_of(R"({"effects": {"xray": {"projector": "exact"}}})").trilinear.slices);
  EXPECT_EQ(error_of(R"({"effects": {"xray": {"projector": "gl", "sampling": "planes"}}})"),
            "test.json: effects.xray.sampling: only with projector \"cpu\" or \"cuda\" (\"gl\" has its own)");
}

TEST(Scene, TheBeatingBackgroundIsOnByDefaultAndItsBinsAreChecked) {
  const Scene d = default_scene();
  ASSERT_TRUE(d.xray && d.world.vessel_motion);
  EXPECT_EQ(d.xray->heart_phase_bins, 16);
  EXPECT_TRUE(d.xray->heart_phase_blend);
  const Scene still =
      parse_scene(R"({"effects": {"xray": {"heart_phase_bins": 0, "heart_phase_blend": false}}})", "test.json");
  EXPECT_EQ(still.xray->heart_phase_bins, 0);
  EXPECT_FALSE(still.xray->heart_phase_blend);
  EXPECT_EQ(error_of(R"({"effects": {"xray": {"heart_phase_bins": 1}}})"),
            "test.json: effects.xray.heart_phase_bins: expected 0 (a still background) or 2-64, got 1");
  EXPECT_NE(error_of(R"({"effects": {"xray": {"heart_phase_bins": 65}}})").find("effects.xray.heart_phase_bins"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"effects": {"xray": {"heart_phase_blend": 3}}})").find("effects.xray.heart_phase_blend"),
            std::string::npos);
}

// a 1 GB scene once held the LCM thread for 10 s and locked 2.3 GB: refused before it is read
TEST(Scene, AnOversizedSceneFileIsRefusedUnread) {
  const std::string path = ::testing::TempDir() + "/huge-scene.json";
  {
    std::ofstream out(path);
    out << "{\"effects\": {}, \"name\": \"" << std::string(kMaxSceneFileBytes, 'x') << "\"}";
  }
  try {
    load_scene_file(path);
    FAIL() << "expected json::JsonError";
  } catch (const json::JsonError& e) {
    EXPECT_NE(std::string(e.what()).find("over the 1048576 byte limit"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace pcisim::server

namespace pcisim::server {
namespace {

TEST(Scene, TheKidneySceneListsOnlyTheSoftTissueEffects) {
  const Scene s = load_scene_file(PCISIM_SOURCE_DIR "/scenes/kidney.json");
  EXPECT_EQ(s.effects, (std::vector<std::string>{"soft_tissue", "probe_contact", "ultrasound"}));
  EXPECT_EQ(s.organ, "kidney");
  EXPECT_FALSE(s.world.guidewire || s.world.heart_beat || s.xray);
  ASSERT_TRUE(s.world.soft_tissue && s.world.probe_contact && s.ultrasound);
  EXPECT_DOUBLE_EQ(s.world.soft_tissue->model.particle_radius_m, 3.3e-3);
  EXPECT_EQ(s.world.soft_tissue->params.substeps, 3);
  EXPECT_DOUBLE_EQ(s.world.soft_tissue->params.cluster_compliance_s2, 2e-5);
  EXPECT_DOUBLE_EQ(s.world.soft_tissue->params.bulk_modulus_pa, 100e3);
  EXPECT_EQ(s.world.soft_tissue->params.contact_surface, physics::soft_tissue::ContactSurface::kSpheres);
  EXPECT_DOUBLE_EQ(s.world.probe_contact->face_width_m, 0.040);
  EXPECT_NEAR(s.world.probe_contact->start_position_m.y(), -0.030, 1e-15);
  EXPECT_EQ(s.ultrasound->settings.geometry, ultrasound::ProbeGeometry::kLinear);
  EXPECT_DOUBLE_EQ(s.ultrasound->settings.depth_mm, 60.0);
  EXPECT_DOUBLE_EQ(s.ultrasound->frame_rate_hz, 20.0);
  EXPECT_EQ(s.ultrasound->settings.renderer, ultrasound::UsRenderer::kCpu);
}

// the GPU's kidney: the CPU scene but for its solver (Jacobi on the device, 27 iterations: the
// Jacobi calibration's); the organ, its stiffness, contacts and probe as scenes/kidney.json has them
TEST(Scene, TheGpuKidneySceneIsTheCpuOneWithTheDevicesSolver) {
  const Scene cpu = load_scene_file(PCISIM_SOURCE_DIR "/scenes/kidney.json");
  const Scene gpu = load_scene_file(PCISIM_SOURCE_DIR "/scenes/kidney-gpu.json");
  EXPECT_EQ(gpu.effects, cpu.effects);
  ASSERT_TRUE(gpu.world.soft_tissue && gpu.world.probe_contact && gpu.ultrasound);
  const physics::soft_tissue::TissueParams& g = gpu.world.soft_tissue->params;
  const physics::soft_tissue::TissueParams& c = cpu.world.soft_tissue->params;
  EXPECT_EQ(g.solver, physics::pbd::SolverKind::kJacobiCuda);
  EXPECT_EQ(c.solver, physics::pbd::SolverKind::kGaussSeidel);
  EXPECT_EQ(g.iterations, 27);
  EXPECT_DOUBLE_EQ(g.sor_w, 1.5);
  EXPECT_EQ(g.substeps, c.substeps);
  EXPECT_DOUBLE_EQ(g.cluster_compliance_s2, 2e-5);
  EXPECT_DOUBLE_EQ(g.bulk_modulus_pa, 100e3);
  EXPECT_EQ(g.contact_surface, c.contact_surface);
  EXPECT_DOUBLE_EQ(g.damping_per_s, c.damping_per_s);
  EXPECT_DOUBLE_EQ(g.density_kg_per_m3, c.density_kg_per_m3);
  EXPECT_DOUBLE_EQ(g.support_mu_static, c.support_mu_static);
  EXPECT_DOUBLE_EQ(g.probe_mu_static, c.probe_mu_static);
  EXPECT_EQ(g.stabilisation_iterations, c.stabilisation_iterations);
  EXPECT_DOUBLE_EQ(gpu.world.soft_tissue->settle_s, cpu.world.soft_tissue->settle_s);
  EXPECT_DOUBLE_EQ(gpu.world.soft_tissue->model.particle_radius_m, cpu.world.soft_tissue->model.particle_radius_m);
  EXPECT_DOUBLE_EQ(gpu.world.probe_contact->face_width_m, cpu.world.probe_contact->face_width_m);
  EXPECT_EQ(gpu.ultrasound->settings.width_px, cpu.ultrasound->settings.width_px);
}

TEST(Scene, SoftTissueMistakesNameTheirPath) {
  const std::string organ = R"("anatomy": {"organ": "kidney"}, )";
  EXPECT_EQ(error_of("{" + organ + R"("effects": {"soft_tissue": {}, "guidewire": {}}})"),
            "test.json: effects.soft_tissue: does not go with effect \"guidewire\" (the soft-tissue scene's anatomy "
            "is an organ)");
  EXPECT_EQ(error_of(R"({"effects": {"soft_tissue": {}}})"),
            "test.json: effects.soft_tissue: needs an organ (anatomy.organ: \"kidney\", or anatomy.case: a case "
            "folder with an organ)");
  EXPECT_EQ(error_of("{" + organ + R"("effects": {"probe_contact": {}}})"),
            "test.json: effects.probe_contact: needs effect \"soft_tissue\" in the same scene");
  EXPECT_EQ(error_of("{" + organ + R"("effects": {"soft_tissue": {}, "ultrasound": {}}})"),
            "test.json: effects.ultrasound: needs effect \"probe_contact\" in the same scene");
  EXPECT_EQ(error_of("{" + organ + R"("effects": {"soft_tissue": {"particle_radius_mm": 50}}})"),
            "test.json: effects.soft_tissue.particle_radius_mm: expected a number in [1.5, 20], got 50");
  {
    const Scene skin =
        parse_scene("{" + organ + R"("effects": {"soft_tissue": {"contact_surface": "skin"}}})", "test.json");
    EXPECT_EQ(skin.world.soft_tissue->params.contact_surface, physics::soft_tissue::ContactSurface::kSkin);
  }
  EXPECT_EQ(error_of("{" + organ + R"("effects": {"soft_tissue": {"contact_surface": "mesh"}}})"),
            "test.json: effects.soft_tissue.contact_surface: expected one of \"spheres\", \"skin\", got \"mesh\"");
  EXPECT_EQ(error_of("{" + organ + R"("effects": {"soft_tissue": {"bulk_modulus_pa": -1}}})"),
            "test.json: effects.soft_tissue.bulk_modulus_pa: expected a number in [0, 1000000000], got -1");
  EXPECT_EQ(error_of("{" + organ + R"("effects": {"soft_tissue": {"solver": "sor"}}})"),
            "test.json: effects.soft_tissue.solver: expected one of \"gauss_seidel\", \"jacobi\", got \"sor\"");
  {
    // the whole step on the GPU: the Jacobi solver's device twin, with or without "solver": "jacobi"
    for (const char* tissue : {R"({"device": "cuda"})", R"({"device": "cuda", "solver": "jacobi"})"}) {
      const Scene gpu = parse_scene("{" + organ + R"("effects": {"soft_tissue": )" + tissue + "}}", "test.json");
      EXPECT_EQ(gpu.world.soft_tissue->params.solver, physics::pbd::SolverKind::kJacobiCuda) << tissue;
    }
    const Scene cpu = parse_scene("{" + organ + R"("effects": {"soft_tissue": {"device": "cpu"}}})", "test.json");
    EXPECT_EQ(cpu.world.soft_tissue->params.solver, physics::pbd::SolverKind::kGaussSeidel);
  }
  EXPECT_EQ(error_of("{" + organ + R"("effects": {"soft_tissue": {"device": "cuda", "solver": "gauss_seidel"}}})"),
            "test.json: effects.soft_tissue.device: \"cuda\" solves with Jacobi: set solver \"jacobi\" or leave it "
            "out");
  EXPECT_EQ(error_of("{" + organ + R"("effects": {"soft_tissue": {"device": "gpu"}}})"),
            "test.json: effects.soft_tissue.device: expected one of \"cpu\", \"cuda\", got \"gpu\"");
  EXPECT_EQ(error_of("{" + organ +
                     R"("effects": {"soft_tissue": {}, "probe_contact": {"start_orientation_wxyz": [0,0,0,0]}}})"),
            "test.json: effects.probe_contact.start_orientation_wxyz: expected a non-zero quaternion [w, x, y, z]");
  EXPECT_EQ(
      error_of("{" + organ + R"("effects": {"soft_tissue": {}, "probe_contact": {"start_position_mm": [0, 1]}}})"),
      "test.json: effects.probe_contact.start_position_mm: expected [x, y, z]");
  EXPECT_EQ(error_of("{" + organ +
                     R"("effects": {"soft_tissue": {}, "probe_contact": {}, "ultrasound": {"depth_mm": 400}}})"),
            "test.json: effects.ultrasound.depth_mm: expected a number in [1, 300], got 400");
  EXPECT_EQ(error_of("{" + organ +
                     R"("effects": {"soft_tissue": {}, "probe_contact": {}, "ultrasound": {"renderer": "gpu"}}})"),
            "test.json: effects.ultrasound.renderer: expected one of \"cpu\", \"cuda\", got \"gpu\"");
  {
    const Scene gpu = parse_scene(
        "{" + organ + R"("effects": {"soft_tissue": {}, "probe_contact": {}, "ultrasound": {"renderer": "cuda"}}})",
        "test.json");
    EXPECT_EQ(gpu.ultrasound->settings.renderer, ultrasound::UsRenderer::kCuda);
  }
  EXPECT_EQ(error_of(R"({"anatomy": {"organ": "kidney"}, "effects": {"guidewire": {}}})"),
            "test.json: anatomy.organ: needs effect \"soft_tissue\" (an organ is the soft-tissue scene's anatomy)");
  EXPECT_EQ(error_of("{" + organ +
                     R"("effects": {"soft_tissue": {}, "probe_contact": {"start_position_mm": [8000, 8000, 0]}}})"),
            "test.json: effects.probe_contact.start_position_mm: expected within 10000 mm of the origin");
  EXPECT_EQ(error_of(R"({"anatomy": {"organ": "liver"}, "effects": {}})"),
            "test.json: anatomy.organ: expected one of \"\", \"kidney\", got \"liver\"");
}

// the soft-tissue scene's organ from a case folder (checked to hold one when it is read:
// tests/server/case_equivalence_test.cc); the procedural kidney and a case at once is refused
TEST(Scene, TheSoftTissueSceneMayTakeItsOrganFromACase) {
  const Scene s =
      parse_scene(R"({"anatomy": {"case": "kidney-case"}, "effects": {"soft_tissue": {}}})", "/data/scenes/k.json");
  EXPECT_EQ(s.case_dir, "/data/scenes/kidney-case");
  EXPECT_EQ(s.organ, "");
  ASSERT_TRUE(s.world.soft_tissue.has_value());
  EXPECT_EQ(error_of(R"({"anatomy": {"organ": "kidney", "case": "k"}, "effects": {"soft_tissue": {}}})"),
            "test.json: anatomy.organ: give either the procedural \"kidney\" or a case folder (which brings its own "
            "organ), not both");
}

}  // namespace
}  // namespace pcisim::server
