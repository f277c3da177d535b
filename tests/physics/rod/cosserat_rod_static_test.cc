// The discrete Cosserat rod's static equilibrium (rod_statics.h: Newton on the same strains as
// the XPBD constraints) against the exact elastica: within 1 % at the default 50 segments for
// load parameters 1 to 10, and second-order convergence in the segment count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "physics/rod/elastica.h"
#include "physics/rod/rod_statics.h"
#include "physics/rod/unit_cantilever.h"

namespace pcisim::physics::rod {
namespace {

CantileverTip static_tip_load(int segments, double alpha) {
  CosseratRod rod = make_unit_cantilever(unit_cantilever(segments));
  rod.set_node_force_n(segments, Eigen::Vector3d(0.0, -alpha, 0.0));
  const StaticSolveResult r = solve_static(rod);
  EXPECT_TRUE(r.converged) << segments << " segments, alpha " << alpha;
  return cantilever_tip(rod);
}

CantileverTip static_self_weight(int segments, double w) {
  CosseratRodParams p = unit_cantilever(segments);
  p.gravity_m_per_s2 = Eigen::Vector3d(0.0, -w, 0.0);  // mu = L = EI = 1: w = mu g L^3 / EI
  CosseratRod rod = make_unit_cantilever(p);
  const StaticSolveResult r = solve_static(rod);
  EXPECT_TRUE(r.converged) << segments << " segments, w " << w;
  return cantilever_tip(rod);
}

double percent(double value, double reference) {
  return 100.0 * std::abs(value - reference) / reference;
}

TEST(CosseratRodStatic, TipLoadWithinOnePercentAtDefaultResolution) {
  const int segments = CosseratRodParams{}.segments;
  ASSERT_EQ(segments, 50);
  for (double alpha : {1.0, 2.0, 5.0, 10.0}) {
    const ElasticaTip exact = cantilever_tip_load(alpha);
    const CantileverTip tip = static_tip_load(segments, alpha);
    std::printf("tip load alpha %4.1f: dv %.3f %% dh %.3f %% angle %.3f %%\n", alpha,
                percent(tip.dv_over_l, exact.dv_over_l), percent(tip.dh_over_l, exact.dh_over_l),
                percent(tip.angle_rad, exact.angle_rad));
    // measured 0.02-0.04 %: the bound is the 1 %, with a tighter guard against regressions
    EXPECT_LT(percent(tip.dv_over_l, exact.dv_over_l), 0.1) << alpha;
    EXPECT_LT(percent(tip.dh_over_l, exact.dh_over_l), 0.1) << alpha;
    EXPECT_LT(percent(tip.angle_rad, exact.angle_rad), 0.1) << alpha;
  }
}

TEST(CosseratRodStatic, TipLoadErrorFallsWithResolutionAtSecondOrder) {
  for (double alpha : {1.0, 10.0}) {
    const double exact = cantilever_tip_load(alpha).dv_over_l;
    double previous = 1e9;
    for (int segments : {10, 20, 40, 80}) {
      const double err = percent(static_tip_load(segments, alpha).dv_over_l, exact);
      std::printf("tip load alpha %4.1f, %2d segments: dv error %.4f %%\n", alpha, segments, err);
      EXPECT_LT(err, previous / 3.0) << alpha << " at " << segments;  // halving l quarters the error
      previous = err;
    }
  }
}

TEST(CosseratRodStatic, SelfWeightWithinOnePercentAtDefaultResolution) {
  for (double w : {1.0, 3.0, 10.0, 30.0}) {
    const ElasticaTip exact = cantilever_self_weight(w);
    const CantileverTip tip = static_self_weight(50, w);
    std::printf("self weight w %4.1f: dv %.3f %% dh %.3f %% angle %.3f %%\n", w,
                percent(tip.dv_over_l, exact.dv_over_l), percent(tip.dh_over_l, exact.dh_over_l),
                percent(tip.angle_rad, exact.angle_rad));
    EXPECT_LT(percent(tip.dv_over_l, exact.dv_over_l), 0.1) << w;
    EXPECT_LT(percent(tip.angle_rad, exact.angle_rad), 0.1) << w;
  }
}

// the clamped-free column under a dead axial load r P_cr: a small lateral push at the tip picks
// the buckled branch (or shows there is none), then the push is removed and Newton converges
CantileverTip static_column(int segments, double load_ratio) {
  CosseratRod rod = make_unit_cantilever(unit_cantilever(segments));
  const double axial_n = load_ratio * euler_load_n(1.0, 1.0);
  rod.set_node_force_n(segments, Eigen::Vector3d(-axial_n, -0.01, 0.0));
  solve_static(rod);  // through the bifurcation: need not converge to the tolerance
  rod.set_node_force_n(segments, Eigen::Vector3d(-axial_n, 0.0, 0.0));
  StaticSolveOptions options;
  options.load_steps = 1;
  EXPECT_TRUE(solve_static(rod, options).converged) << load_ratio;
  return cantilever_tip(rod);
}

TEST(CosseratRodStatic, BuckledColumnWithinOnePercentAtDefaultResolution) {
  // measured at 50 segments: dv +0.08 %, +0.004 %, -0.04 % at P / P_cr = 1.1, 2, 4 (dh 0.17,
  // 0.08, 0.07 %)
  for (double r : {1.1, 2.0, 4.0}) {
    const ElasticaTip exact = column_post_buckling(r);
    const CantileverTip tip = static_column(50, r);
    std::printf("column P/P_cr %.1f: dv %.3f %% dh %.3f %%\n", r, percent(tip.dv_over_l, exact.dv_over_l),
                percent(tip.dh_over_l, exact.dh_over_l));
    EXPECT_LT(percent(tip.dv_over_l, exact.dv_over_l), 0.5) << r;
    EXPECT_LT(percent(tip.dh_over_l, exact.dh_over_l), 0.5) << r;
  }
  // below the Euler load the push is forgotten: the column is straight again
  const CantileverTip below = static_column(50, 0.9);
  EXPECT_LT(std::abs(below.dv_over_l), 1e-6);
}

TEST(CosseratRodStatic, AnswerDoesNotDependOnTheClampsDirection) {
  // the same cantilever clamped along a skew direction, loaded perpendicular to it
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, 2.0, -0.5).normalized();
  const Eigen::Vector3d down = axis.unitOrthogonal();
  CosseratRod rod(unit_cantilever(20), Eigen::Vector3d(0.3, -0.2, 0.1),
                  Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis));
  rod.set_node_force_n(20, 5.0 * down);
  ASSERT_TRUE(solve_static(rod).converged);
  const Eigen::Vector3d d = rod.nodes_m().back() - Eigen::Vector3d(0.3, -0.2, 0.1);
  const CantileverTip reference = static_tip_load(20, 5.0);
  EXPECT_NEAR(d.dot(down), reference.dv_over_l, 1e-7);
  EXPECT_NEAR(1.0 - d.dot(axis), reference.dh_over_l, 1e-7);
}

TEST(CosseratRodStatic, TurningTheClampTwistsTheRodUniformly) {
  // no load: a hub turned by 90 degrees about the tangent turns every frame the same way
  CosseratRod rod = make_unit_cantilever(unit_cantilever(20));
  const Eigen::Quaterniond turned = Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitX()) * along_x();
  rod.set_clamp(Eigen::Vector3d::Zero(), turned);
  ASSERT_TRUE(solve_static(rod).converged);
  for (const Eigen::Quaterniond& q : rod.orientations()) EXPECT_LT(q.angularDistance(turned), 1e-6);
  EXPECT_LT((rod.nodes_m().back() - Eigen::Vector3d(1.0, 0.0, 0.0)).norm(), 1e-9);
}

}  // namespace
}  // namespace pcisim::physics::rod
