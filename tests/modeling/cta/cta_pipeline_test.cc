// The CTA pipeline end to end on a small synthetic CTA with exact truth.
#include "modeling/cta/cta_pipeline.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>

#include "anatomy/phantom/coronary_phantom.h"
#include "anatomy/phantom/thorax_phantom.h"

namespace pcisim::modeling {
namespace {

TEST(CtaPipeline, ThoraxWithBrightBloodGivesATree) {
  anatomy::ThoraxPhantomSpec spec;
  spec.dims = {200, 200, 200};
  spec.spacing_mm = 0.7;
  spec.hu.blood = 420;
  spec.contrast_hu = 420;
  spec.center_mm = Eigen::Vector3d(0, 0, 15);
  const anatomy::VesselTree truth = anatomy::make_coronary_phantom({.seed = 1});
  const anatomy::Volume ct = anatomy::make_thorax_phantom(spec, truth);
  const int a = truth.find("aorta");
  const Eigen::Vector3d seed = truth.branches[a].points[truth.branches[a].points.size() / 2].position_m * 1e3;
  CtaPipelineOptions o;
  o.segmentation.level_set.iterations = 0;
  const CtaModel m = build_cta_model(ct, {seed}, o, [](const StageReport& r, bool done) {
    if (done) std::printf("%s: %.2f s\n", r.name.c_str(), r.seconds);
    if (done) {
      for (const auto& [k, v] : r.figures) std::printf("  %s = %g\n", k.c_str(), v);
      for (const auto& n : r.notes) std::printf("  %s\n", n.c_str());
    }
  });
  EXPECT_GE(m.model.vessels.branches.size(), 5u);
  for (const auto& b : m.model.vessels.branches) {
    double len = anatomy::branch_length_m(b) * 1e3;
    double r = 0;
    for (const auto& p : b.points) r += p.radius_m * 1e3;
    std::printf("%s parent %d at %d: %.1f mm, mean r %.2f mm\n", b.name.c_str(), b.parent, b.parent_point, len,
                r / b.points.size());
  }
}

}  // namespace
}  // namespace pcisim::modeling
