// A scene on `anatomy.case` pointing at the phantom case that --write-case wrote runs the same as
// the scene on `phantom_seed`: the same wire trajectory step by step and the same fluoroscopy
// frames, through the pieces the server wires (build_case -> World, background_volume ->
// FluoroscopyRenderer). And a Server builds on a case folder and names its branches.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "anatomy/case/case_folder.h"
#include "physics/world.h"
#include "server/case_builder.h"
#include "server/server.h"
#include "xray/fluoro/case_background.h"
#include "xray/fluoro/fluoroscopy.h"

namespace pcisim::server {
namespace {

namespace fs = std::filesystem;

// the built-in scene, small X-ray background and detector so the test stays quick
Scene quick_scene(const std::string& anatomy_json, const fs::path& dir) {
  std::string text = default_scene_text();
  Scene s = parse_scene(text, "built-in");
  // the anatomy given as a scene file beside the case, as a user writes it
  const fs::path file = dir / "scene.json";
  nlohmann::json doc = nlohmann::json::parse(text, nullptr, true, /*ignore_comments=*/true);
  doc["anatomy"] = nlohmann::json::parse(anatomy_json);
  doc["effects"]["xray"]["volume_voxels"] = 96;
  doc["effects"]["xray"]["volume_spacing_mm"] = 3.5;  // the whole tree inside the CT
  doc["effects"]["xray"]["detector_px"] = 128;
  std::ofstream(file) << doc.dump(1);
  return load_scene_file(file.string());
}

class CaseEquivalence : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pcisim-case-eq-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(CaseEquivalence, WrittenPhantomCaseRunsLikeItsSeed) {
  const Scene by_seed = quick_scene(R"({"phantom_seed": 4})", dir_);
  ASSERT_TRUE(by_seed.xray.has_value());
  // what `pcisim-server --write-case` writes for this scene
  anatomy::write_case(anatomy::make_phantom_case(phantom_case_spec(by_seed)), (dir_ / "patient").string());
  const Scene by_case = quick_scene(R"({"case": "patient"})", dir_);
  EXPECT_EQ(by_case.case_dir, (dir_ / "patient").string());

  const auto seed_case = build_case(by_seed), file_case = build_case(by_case);
  ASSERT_TRUE(file_case->ct.has_value());

  // physics: the same trajectory, bit for bit, over a push, a twist and a pull
  physics::World a(by_seed.world, seed_case->vessels), b(by_case.world, file_case->vessels);
  physics::WorldSnapshot sa, sb;
  physics::InstrumentInput in;
  for (int step = 0; step < 240; ++step) {
    in.insertion_m = step < 160 ? 0.0006 * step : 0.096 - 0.0003 * (step - 160);
    in.rotation_rad = 0.02 * step;
    a.step(in);
    b.step(in);
    a.write_snapshot(sa);
    b.write_snapshot(sb);
    ASSERT_EQ(sa.wire_nodes_m, sb.wire_nodes_m) << "step " << step;
    ASSERT_EQ(sa.tip_branch, sb.tip_branch) << "step " << step;
  }
  EXPECT_GT(sa.wire_nodes_m.size(), 10u);

  // x-ray: the same frames (background, wire, contrast, noise) at two poses
  xray::FluoroscopyRenderer ra(seed_case->vessels, xray::background_volume(*seed_case, by_seed.xray->fluoro),
                               by_seed.xray->fluoro);
  xray::FluoroscopyRenderer rb(file_case->vessels, xray::background_volume(*file_case, by_case.xray->fluoro),
                               by_case.xray->fluoro);
  const xray::ContrastInjection inj{.start_s = 0.0, .duration_s = 1.0, .volume_ml = 6.0};
  for (double primary : {0.0, 30.0}) {
    xray::FluoroInput fi;
    fi.time_s = 0.8;
    fi.pose.primary_deg = primary;
    fi.wire_m = sa.wire_nodes_m;
    fi.injections = {&inj, 1};
    xray::FluoroFrame fa, fb;
    ra.render(fi, fa);
    rb.render(fi, fb);
    ASSERT_GT(fa.pixels.size(), 0u);
    EXPECT_EQ(fa.pixels, fb.pixels) << "pose " << primary;
  }
}

TEST_F(CaseEquivalence, ACtAngiogramIsProjectedWithBloodInItsLumens) {
  // the same phantom written as a CTA (iodine in the lumens): its background comes back as the
  // blood-filled one everywhere but at the lumens' partial-volume rims
  Scene s = quick_scene(R"({"phantom_seed": 2})", dir_);
  anatomy::PhantomCaseSpec p = phantom_case_spec(s);
  p.ct_dims = {128, 128, 96};  // 1 mm voxels: the lumens span a few voxels
  p.ct_spacing_mm = 1.0;
  const anatomy::Case plain = anatomy::make_phantom_case(p);
  p.ct_contrast = true;
  const anatomy::Case cta = anatomy::make_phantom_case(p);
  ASSERT_TRUE(cta.ct_lumen_enhanced);
  const anatomy::Volume filled = xray::background_volume(cta, s.xray->fluoro);
  int64_t differ_before = 0, differ_after = 0;
  for (int64_t n = 0; n < plain.ct->voxel_count(); ++n) {
    differ_before += cta.ct->hu_i16[n] != plain.ct->hu_i16[n];
    differ_after += filled.hu_i16[n] != plain.ct->hu_i16[n];
  }
  EXPECT_GT(differ_before, 1000);
  EXPECT_LT(differ_after, differ_before / 10) << differ_before << " -> " << differ_after;
}

TEST_F(CaseEquivalence, ServerBuildsOnACaseAndRefusesABadOne) {
  Scene s = quick_scene(R"({"phantom_seed": 1})", dir_);
  anatomy::write_case(anatomy::make_phantom_case(phantom_case_spec(s)), (dir_ / "c").string());
  s.case_dir = (dir_ / "c").string();
  lcm::LCM lcm("memq://");
  Server server(s, lcm);
  EXPECT_EQ(server.branch_namer(2), "LAD");
  // a case whose vessels file is gone is refused naming it
  fs::remove(dir_ / "c" / "vessels.json");
  try {
    Server bad(s, lcm);
    ADD_FAILURE() << "a case without vessels.json was built";
  } catch (const anatomy::CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("vessels: file 'vessels.json' not found"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pcisim::server
