// A scene on `anatomy.case` pointing at the phantom case that --write-case wrote runs the same as
// the scene on `phantom_seed`: the same wire trajectory step by step and the same fluoroscopy
// frames, through the pieces the server wires (build_case -> World, background_volume ->
// FluoroscopyRenderer). And a Server builds on a case folder and names its branches. The kidney
// scene on the organ case --write-case writes for it builds the procedural kidney's tissue, and a
// case that does not fit its scene (no organ for the kidney, no vessels for the wire) is refused.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "anatomy/case/case_folder.h"
#include "physics/soft_tissue/tissue_scene.h"
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

// scenes/kidney.json with 5 mm particles (quick to build), its anatomy given, as a file beside the case
Scene kidney_scene(const std::string& anatomy_json, const fs::path& dir) {
  std::ifstream in(PCISIM_SOURCE_DIR "/scenes/kidney.json");
  nlohmann::json doc = nlohmann::json::parse(in, nullptr, true, /*ignore_comments=*/true);
  doc["anatomy"] = nlohmann::json::parse(anatomy_json);
  doc["effects"]["soft_tissue"]["particle_radius_mm"] = 5;
  const fs::path file = dir / "kidney-scene.json";
  std::ofstream(file) << doc.dump(1);
  return load_scene_file(file.string());
}

// the CaseError build_case gives, or ""
std::string refusal(const Scene& s) {
  try {
    build_case(s);
  } catch (const anatomy::CaseError& e) {
    return e.what();
  }
  return "";
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
  for (int step = 0; step < 160; ++step) {
    in.insertion_m = step < 110 ? 0.0006 * step : 0.066 - 0.0003 * (step - 110);
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

// what `pcisim-server --scene scenes/kidney.json --write-case DIR` writes, run by the kidney scene
// naming it (anatomy.case) or given by --case (which replaces the scene's procedural kidney): the
// same particles and beads as the procedural kidney, to the STL's float rounding of its surface
TEST_F(CaseEquivalence, WrittenKidneyCaseBuildsTheProceduralKidneysTissue) {
  const Scene procedural = kidney_scene(R"({"organ": "kidney", "phantom_seed": 1})", dir_);
  // (build_case's kidney is kidney_case(scene), what --write-case writes: the phantom built once,
  // the test's longest step under ASan)
  const auto a = build_case(procedural);
  anatomy::write_case(*a, (dir_ / "kidney").string());
  const Scene by_case = kidney_scene(R"({"case": "kidney"})", dir_);
  EXPECT_EQ(by_case.case_dir, (dir_ / "kidney").string());
  EXPECT_TRUE(by_case.organ.empty());
  Scene by_option = procedural;
  use_case_folder(by_option, (dir_ / "kidney").string());

  const physics::World wa(procedural.world, a->vessels, nullptr, a->heart, a->heart_vertices_m, &*a->organ);
  const physics::soft_tissue::TissueScene& ta = *wa.tissue_state();
  EXPECT_GT(ta.body().particle_count(), 100);
  for (const Scene* s : {&by_case, static_cast<const Scene*>(&by_option)}) {
    const auto b = build_case(*s);
    ASSERT_TRUE(b->organ.has_value());
    ASSERT_TRUE(b->ct.has_value());
    EXPECT_EQ(b->ct->hu_i16, a->ct->hu_i16);  // what the ultrasound images
    EXPECT_EQ(b->ct->origin_mm, a->ct->origin_mm);
    const physics::World wb(s->world, b->vessels, nullptr, b->heart, b->heart_vertices_m, &*b->organ);
    const physics::soft_tissue::TissueScene& tb = *wb.tissue_state();
    // the model: the surface came back bit for bit (organ.ply), so the same particles, clusters
    // and tets (at 5 mm the particles' spacing ties with the 1 mm voxels: an ulp off in the
    // surface's bounding box gave 988 particles instead of 982)
    ASSERT_EQ(tb.body().particle_count(), ta.body().particle_count());
    EXPECT_EQ(tb.model().rest_m, ta.model().rest_m);
    EXPECT_EQ(tb.model().clusters, ta.model().clusters);
    EXPECT_EQ(tb.model().tets, ta.model().tets);
    // the beads after construction (the organ settled on its support): their centres and the
    // support's offset went through millimetres in JSON, an ulp or so
    ASSERT_EQ(tb.fiducials_m().cols(), ta.fiducials_m().cols());
    ASSERT_EQ(tb.fiducials_m().cols(), 45);
    const double worst_m = (tb.fiducials_m() - ta.fiducials_m()).cwiseAbs().maxCoeff();
    std::printf("beads after construction: %.3g m apart at most\n", worst_m);
    EXPECT_LT(worst_m, 1e-9);
  }
}

// a case must hold what its scene simulates; one holding more (a coronary case with an organ)
// runs the coronary scene as before
TEST_F(CaseEquivalence, ACaseThatDoesNotFitItsSceneIsRefusedNamingTheFolder) {
  Scene coronary = quick_scene(R"({"phantom_seed": 1})", dir_);
  anatomy::write_case(anatomy::make_phantom_case(phantom_case_spec(coronary)), (dir_ / "coronary").string());
  Scene kidney = kidney_scene(R"({"organ": "kidney"})", dir_);
  const anatomy::Case kidney_built = kidney_case(kidney);  // (the phantom built once: slow under ASan)
  anatomy::write_case(kidney_built, (dir_ / "kidney").string());
  // the kidney scene on a coronary case
  use_case_folder(kidney, (dir_ / "coronary").string());
  EXPECT_EQ(refusal(kidney),
            (dir_ / "coronary" / "case.json").string() +
                ": organ: missing (the soft-tissue scene needs a case with an organ; docs/anatomy.md)");
  // the coronary scene on the organ case
  use_case_folder(coronary, (dir_ / "kidney").string());
  EXPECT_NE(refusal(coronary).find((dir_ / "kidney" / "case.json").string() + ": vessels: missing"), std::string::npos)
      << refusal(coronary);
  // a coronary case that also holds an organ: the coronary scene's server builds and names its branches
  anatomy::Case both = anatomy::make_phantom_case(phantom_case_spec(coronary));
  both.organ = kidney_built.organ;
  both.organ->tissue.reset();  // its tissue map lies on the kidney's CT, not this case's
  anatomy::write_case(both, (dir_ / "both").string());
  use_case_folder(coronary, (dir_ / "both").string());
  lcm::LCM lcm("memq://");
  Server server(coronary, lcm);
  EXPECT_EQ(server.branch_namer(2), "LAD");
  // the kidney scene (ultrasound) on a case whose tissue map names a tissue the ultrasound does
  // not know (a Slicer labelmap's "Background"): refused naming case.json's field
  const fs::path case_json = dir_ / "kidney" / "case.json";
  nlohmann::json doc = nlohmann::json::parse(std::ifstream(case_json));
  doc["organ"]["tissue"]["names"][0] = "Background";
  std::ofstream(case_json) << doc.dump(1);
  use_case_folder(kidney, (dir_ / "kidney").string());
  EXPECT_NE(refusal(kidney).find(case_json.string() +
                                 ": organ.tissue.names[0]: \"Background\" has no acoustic properties (known: air, "),
            std::string::npos)
      << refusal(kidney);
  // a scene put together in code with both the procedural organ and a case folder
  Scene two = kidney_scene(R"({"organ": "kidney"})", dir_);
  two.case_dir = (dir_ / "kidney").string();
  EXPECT_THROW(build_case(two), std::invalid_argument);
}

}  // namespace
}  // namespace pcisim::server
