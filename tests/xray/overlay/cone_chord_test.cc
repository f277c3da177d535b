#include "xray/overlay/cone_chord.h"

#include <gtest/gtest.h>

#include <random>

namespace pcisim::xray {
namespace {

// length of the source -> p segment inside the truncated cone, by dense sampling
double sampled_chord(const Eigen::Vector3d& s, const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                     const Eigen::Vector3d& b, double ra, double rb) {
  // only the stretch of the ray within a sphere around the cone (steps of ~0.1 um)
  const int n = 200000;
  const Eigen::Vector3d ab = b - a, d = p - s;
  const double len = d.norm(), half = 0.5 * ab.norm() + std::max(ra, rb) + 1.0;
  const double tc = (0.5 * (a + b) - s).dot(d) / (len * len), t0 = tc - half / len, t1 = tc + half / len;
  int inside = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d x = s + (t0 + (t1 - t0) * (i + 0.5) / n) * d;
    const double u = (x - a).dot(ab) / ab.squaredNorm();
    if (u < 0 || u > 1) continue;
    const double r = ra + u * (rb - ra);
    if ((x - a - u * ab).squaredNorm() <= r * r) ++inside;
  }
  return (t1 - t0) * len * inside / n;
}

TEST(ConeChord, MatchesSampledChordsThroughTaperedCones) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  const Eigen::Vector3d s(0, 750, 0);
  int hits = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d a(3 * u(rng), 3 * u(rng), 3 * u(rng));
    const Eigen::Vector3d b = a + Eigen::Vector3d(4 * u(rng), 2 * u(rng), 4 * u(rng));
    const double ra = 1.5 + u(rng), rb = 1.5 + u(rng);
    const Eigen::Vector3d p(4 * u(rng), -350, 4 * u(rng));  // a detector point behind the cone
    ConeChord cone;
    ASSERT_TRUE(cone.set(s, a, b, ra, rb));
    const double got = cone.chord_mm(p - s), want = sampled_chord(s, p, a, b, ra, rb);
    EXPECT_NEAR(got, want, 2e-4) << trial;  // two sampling steps
    if (want > 0) ++hits;
  }
  EXPECT_GT(hits, 30) << "enough rays cross a cone";
}

TEST(ConeChord, EqualRadiiIsTheCylinderAcrossItsAxis) {
  ConeChord c;
  ASSERT_TRUE(c.set(Eigen::Vector3d(0, 750, 0), Eigen::Vector3d(-5, 0, 0), Eigen::Vector3d(5, 0, 0), 1.0, 1.0));
  // the central ray, 0.6 mm from the axis: chord 2 sqrt(1 - 0.36)
  EXPECT_NEAR(c.chord_mm(Eigen::Vector3d(0, -1100, 0.6 * 1100 / 750)), 1.6, 1e-3);
  EXPECT_FALSE(c.set(Eigen::Vector3d(0, 750, 0), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1, 1));
}

}  // namespace
}  // namespace pcisim::xray
