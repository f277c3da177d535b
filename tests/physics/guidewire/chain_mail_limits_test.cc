// The chain-mail's limits derived from the section (chain_mail_limits.h): a core of known
// diameter gives back its diameter and the elastic curvature 2 eps / d; the stretch limits are
// the axial strain at the hub's largest load; the links use the derived limits; and the default
// wire with a nitinol core's limits still follows the trainee's script into the LAD subtree.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "physics/guidewire/chain_mail_limits.h"
#include "physics/guidewire/chain_mail_wire.h"
#include "physics/guidewire/link_spec.h"
#include "tests/physics/guidewire/wire_test_support.h"
#include "tests/common/shared_lumen.h"

namespace pcisim::physics {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

// EI of a round core of diameter d
double bending_stiffness(double e_pa, double d_m) {
  return e_pa * std::numbers::pi * std::pow(d_m, 4) / 64.0;
}

TEST(ChainMailLimits, ARoundCoreGivesBackItsDiameterAndItsElasticCurvature) {
  // a 0.2 mm spring-steel body core and a 0.06 mm tip core: at 0.6 % surface strain they bend to
  // radii of d / (2 eps) = 16.7 mm and 5 mm, i.e. 60 /m and 200 /m
  GuidewireParams p;
  p.chain_mail_limits = ChainMailLimits::kSteelCore;
  p.bending_stiffness_nm2 = bending_stiffness(200e9, 0.2e-3);
  p.tip_bending_stiffness_nm2 = bending_stiffness(200e9, 0.06e-3);
  const DerivedChainMailLimits d = derive_chain_mail_limits(p);
  EXPECT_NEAR(d.body_core_diameter_m, 0.2e-3, 1e-12);
  EXPECT_NEAR(d.tip_core_diameter_m, 0.06e-3, 1e-12);
  EXPECT_NEAR(d.body_beta_deg_per_mm, 60.0 * kDegPerRad * 1e-3, 1e-9);
  EXPECT_NEAR(d.tip_beta_deg_per_mm, 200.0 * kDegPerRad * 1e-3, 1e-9);
  // the hub's 1 N over each core's E A: 200 GPa x pi (0.1 mm)^2 = 6.28 kN, and (0.03 mm)^2: 565 N
  EXPECT_NEAR(d.body_alpha_max - 1.0, 1.0 / (200e9 * std::numbers::pi * 0.1e-3 * 0.1e-3), 1e-12);
  EXPECT_NEAR(1.0 - d.tip_alpha_min, 1.0 / (200e9 * std::numbers::pi * 0.03e-3 * 0.03e-3), 1e-12);
  // nitinol: a third of steel's modulus, ten times its recoverable strain; the same EI is a
  // thicker core (x (200/60)^(1/4)) that bends 10 / 1.35 = 7.4 times further
  p.chain_mail_limits = ChainMailLimits::kNitinolCore;
  const DerivedChainMailLimits n = derive_chain_mail_limits(p);
  EXPECT_NEAR(n.body_core_diameter_m / d.body_core_diameter_m, std::pow(200.0 / 60.0, 0.25), 1e-12);
  EXPECT_NEAR(n.body_beta_deg_per_mm / d.body_beta_deg_per_mm, 10.0 / std::pow(200.0 / 60.0, 0.25), 1e-9);
  // a very soft tip's limit is capped at the scene range's 90 deg per mm
  p.tip_bending_stiffness_nm2 = 1e-9;
  EXPECT_EQ(derive_chain_mail_limits(p).tip_beta_deg_per_mm, kGuidewireBetaDegPerMm.max);
  p.chain_mail_limits = ChainMailLimits::kGiven;
  EXPECT_THROW(derive_chain_mail_limits(p), std::invalid_argument);
}

TEST(ChainMailLimits, TheLinksUseTheDerivedLimitsAndGivenOnesStayAsSet) {
  GuidewireParams p;  // 200 segments of 1.5 mm
  const auto given = make_link_specs(p);
  EXPECT_NEAR(given.front().beta_rad, p.body_beta_deg_per_mm * 1.5 / kDegPerRad, 1e-12);
  EXPECT_NEAR(given.front().length_max_m, p.body_alpha_max * 1.5e-3, 1e-15);
  p.chain_mail_limits = ChainMailLimits::kNitinolCore;
  const DerivedChainMailLimits d = derive_chain_mail_limits(p);
  const auto derived = make_link_specs(p);
  EXPECT_NEAR(derived.front().beta_rad, d.body_beta_deg_per_mm * 1.5 / kDegPerRad, 1e-12);
  EXPECT_NEAR(derived.back().beta_rad, std::min(d.tip_beta_deg_per_mm * 1.5 / kDegPerRad, std::numbers::pi / 2), 1e-12);
  EXPECT_NEAR(derived.front().length_max_m, d.body_alpha_max * 1.5e-3, 1e-15);
  std::printf(
      "default section, nitinol core: body d %.3f mm beta %.1f deg/mm, tip d %.3f mm beta %.1f deg/mm; steel core: "
      "body beta %.2f, tip %.2f deg/mm; alpha 1 -+ %.2e (given: body 15, tip 40 deg/mm, alpha 1 -+ 0.02)\n",
      1e3 * d.body_core_diameter_m, d.body_beta_deg_per_mm, 1e3 * d.tip_core_diameter_m, d.tip_beta_deg_per_mm,
      [] {
        GuidewireParams s;
        s.chain_mail_limits = ChainMailLimits::kSteelCore;
        return derive_chain_mail_limits(s).body_beta_deg_per_mm;
      }(),
      [] {
        GuidewireParams s;
        s.chain_mail_limits = ChainMailLimits::kSteelCore;
        return derive_chain_mail_limits(s).tip_beta_deg_per_mm;
      }(),
      d.body_alpha_max - 1.0);
}

TEST(ChainMailLimits, ANitinolCoresLimitsStillFollowTheTraineeIntoTheLad) {
  WorldSpec spec = test::default_scene();
  spec.guidewire->chain_mail_limits = ChainMailLimits::kNitinolCore;
  World world = test::make_world(spec);
  test::BranchScript script;
  for (double t = 0.0; t <= script.end_s(); t += spec.step_s) world.step(script.at(t));
  WorldSnapshot snap;
  world.write_snapshot(snap);
  const anatomy::VesselTree& tree = world.vessel_tree();
  const int lad = tree.find("LAD");
  bool in_lad = false;
  for (int b = snap.tip_branch; b >= 0; b = tree.branches[b].parent) in_lad = in_lad || b == lad;
  EXPECT_TRUE(in_lad) << tree.branches[snap.tip_branch].name;
  for (const auto& x : world.guidewire_state()->nodes_m()) ASSERT_TRUE(x.allFinite());
}

}  // namespace
}  // namespace pcisim::physics
