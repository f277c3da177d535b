// The named wires: each preset's tip, as a 10 mm clamped-free rod of the preset's tip stiffness,
// stays straight under 90 % of the wire's stated tip load and at 110 % stands where the exact
// post-buckled column does (the discrete rod's own static solve against the elliptic-integral
// elastica, not the formula that set the stiffness); presets set the rod's section and an
// unknown name is refused naming the known ones.
#include "physics/guidewire/wire_presets.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "physics/rod/cosserat_rod.h"
#include "physics/rod/elastica.h"
#include "physics/rod/rod_statics.h"

namespace pcisim::physics {
namespace {

// the tip, 10 mm, clamped along +x, pushed back along -x with `load_n` after a small sideways
// nudge is removed; returns the tip's sideways deflection over the length
double tip_sideways_after_push(double tip_stiffness_nm2, double load_n) {
  rod::CosseratRodParams p;
  p.length_m = 0.010;
  p.segments = 40;
  p.bending_stiffness_nm2 = tip_stiffness_nm2;
  p.torsional_stiffness_nm2 = 0.77 * tip_stiffness_nm2;
  p.axial_stiffness_n = 1e4;
  p.shear_stiffness_n = 1e4;
  rod::CosseratRod tip(p, Eigen::Vector3d::Zero(),
                       Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()));
  tip.set_node_force_n(p.segments, Eigen::Vector3d(-load_n, -0.01 * load_n, 0.0));
  rod::solve_static(tip);
  tip.set_node_force_n(p.segments, Eigen::Vector3d(-load_n, 0.0, 0.0));
  rod::StaticSolveOptions once;
  once.load_steps = 1;
  rod::solve_static(tip, once);  // judged by its answer against the elastica below
  return std::abs(tip.nodes_m().back().y()) / p.length_m;
}

TEST(WirePresets, EachTipBucklesAtItsStatedTipLoad) {
  for (const WirePreset& w : wire_presets()) {
    GuidewireParams g;
    apply_wire_preset(w.name, &g);
    const double load_n = w.tip_load_gf * 9.80665e-3;
    const double above = tip_sideways_after_push(g.tip_bending_stiffness_nm2, 1.1 * load_n);
    const double below = tip_sideways_after_push(g.tip_bending_stiffness_nm2, 0.9 * load_n);
    std::printf("%-12s (%s, %.1f gf): tip EI %.3g N m^2; sideways at 1.1 x load %.3f L, at 0.9 x %.1e L\n",
                std::string(w.name).c_str(), std::string(w.modelled_on).c_str(), w.tip_load_gf,
                g.tip_bending_stiffness_nm2, above, below);
    // above the buckling load the tip stands where the exact post-buckled column does
    EXPECT_NEAR(above, rod::column_post_buckling(1.1).dv_over_l, 0.01 * above) << w.name;
    EXPECT_LT(below, 1e-6) << w.name;
  }
}

TEST(WirePresets, APresetSetsTheRodsSectionAndTheStiffTipIsStiffer) {
  GuidewireParams workhorse, stiff, support;
  apply_wire_preset("workhorse", &workhorse);
  apply_wire_preset("stiff_tip", &stiff);
  apply_wire_preset("support", &support);
  EXPECT_NEAR(workhorse.tip_bending_stiffness_nm2, tip_stiffness_from_load_nm2(0.6, 0.010), 1e-20);
  EXPECT_NEAR(stiff.tip_bending_stiffness_nm2 / workhorse.tip_bending_stiffness_nm2, 10.0, 1e-9);
  EXPECT_GT(support.bending_stiffness_nm2, workhorse.bending_stiffness_nm2);
  // the 0.6 gf tip: 4 L^2 P / pi^2 = 4e-4 m^2 x 5.884e-3 N / 9.8696 = 2.385e-7 N m^2
  EXPECT_NEAR(workhorse.tip_bending_stiffness_nm2, 2.385e-7, 1e-10);
}

TEST(WirePresets, AnUnknownNameIsRefusedNamingTheKnownOnes) {
  GuidewireParams g;
  try {
    apply_wire_preset("bmw", &g);
    FAIL() << "accepted an unknown preset";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("workhorse, hydrophilic, support, stiff_tip"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pcisim::physics
