// The named wires: each preset's tip, as a 10 mm clamped-free rod of the preset's tip stiffness,
// stays straight under 90 % of the tip load cited for its wire (written out here, not read from
// the preset) and at 110 % stands where the exact post-buckled column does (the discrete rod's own
// static solve against the elliptic-integral elastica, not the formula that set the stiffness);
// presets set the rod's section and an unknown name is refused naming the known ones.
#include "physics/guidewire/wire_presets.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <stdexcept>
#include <string>

#include "physics/rod/cosserat_rod.h"
#include "physics/rod/elastica.h"
#include "physics/rod/rod_statics.h"

namespace pcisim::physics {
namespace {

// the cited figures, written out here rather than read from the presets: the wire each preset is
// modelled on and its stated tip load (wire_presets.cc's source comment and docs/guidewire.md,
// "Presets": the guidewire-reference app's LibraryData.jsx), and the free length of the tip-load
// convention, 10 mm
struct Cited {
  const char* name;
  const char* wire;
  double tip_load_gf;
};
constexpr Cited kCited[] = {{"workhorse", "Abbott Hi-Torque BMW", 0.6},
                            {"hydrophilic", "Asahi Fielder FC", 0.8},
                            {"support", "Abbott Iron Man", 1.0},
                            {"stiff_tip", "Asahi Miracle 6", 6.0}};
constexpr double kCitedTipLengthM = 0.010;
constexpr double kGramForceN = 9.80665e-3;

// the tip, 10 mm, clamped along +x, pushed back along -x with `load_n` after a small sideways
// nudge is removed; returns the tip's sideways deflection over the length
double tip_sideways_after_push(double tip_stiffness_nm2, double load_n) {
  rod::CosseratRodParams p;
  p.length_m = kCitedTipLengthM;
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
  ASSERT_EQ(wire_presets().size(), std::size(kCited));
  for (const Cited& c : kCited) {
    GuidewireParams g;
    apply_wire_preset(c.name, &g);
    const auto it = std::find_if(wire_presets().begin(), wire_presets().end(),
                                 [&](const WirePreset& w) { return w.name == c.name; });
    ASSERT_NE(it, wire_presets().end()) << c.name;
    EXPECT_NE(std::string(it->modelled_on).find(c.wire), std::string::npos) << c.name << ": " << it->modelled_on;
    // the rod of the preset's tip EI, as long as the cited free length, under the cited load
    const double load_n = c.tip_load_gf * kGramForceN;
    const double above = tip_sideways_after_push(g.tip_bending_stiffness_nm2, 1.1 * load_n);
    const double below = tip_sideways_after_push(g.tip_bending_stiffness_nm2, 0.9 * load_n);
    std::printf("%-12s (%s, %.1f gf): tip EI %.3g N m^2; sideways at 1.1 x load %.3f L, at 0.9 x %.1e L\n", c.name,
                c.wire, c.tip_load_gf, g.tip_bending_stiffness_nm2, above, below);
    // above the buckling load the tip stands where the exact post-buckled column does (0.509 L)
    EXPECT_NEAR(above, rod::column_post_buckling(1.1).dv_over_l, 0.01 * above) << c.name;
    EXPECT_LT(below, 1e-6) << c.name;  // measured 2e-10 L
  }
}

TEST(WirePresets, APresetSetsTheRodsSectionAndTheStiffTipIsStiffer) {
  // Euler's clamped-free column, EI = 4 L^2 P / pi^2, written out with the cited loads at 10 mm:
  // 4 x 1e-4 m^2 x (0.6, 0.8, 1.0, 6.0) x 9.80665e-3 N / 9.8696
  const double expected_tip_ei_nm2[] = {2.3847e-7, 3.1796e-7, 3.9745e-7, 2.3847e-6};
  for (size_t i = 0; i < std::size(kCited); ++i) {
    GuidewireParams g;
    apply_wire_preset(kCited[i].name, &g);
    EXPECT_NEAR(g.tip_bending_stiffness_nm2 / expected_tip_ei_nm2[i], 1.0, 2e-4) << kCited[i].name;
    // the body: the default steel-core estimate, x 3 for the support wire (docs/guidewire.md)
    const double body_scale = std::string(kCited[i].name) == "support" ? 3.0 : 1.0;
    EXPECT_NEAR(g.bending_stiffness_nm2, body_scale * 1.56e-5, 1e-12) << kCited[i].name;
    EXPECT_NEAR(g.torsional_rigidity_nm2, body_scale * 1.2e-5, 1e-12) << kCited[i].name;
  }
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
