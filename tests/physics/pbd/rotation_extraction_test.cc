// Rotation extraction: always a proper rotation, and the true one for a rigidly moved cluster.
#include "physics/pbd/rotation_extraction.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "tests/physics/pbd/pbd_test_bodies.h"

namespace pcisim::physics::pbd {
namespace {

using testing::random_rotation;

struct Moments {
  Eigen::Matrix3d a;
  double rest_moment;
};

// A_pq = sum m p q^T for rest offsets q (columns) mapped to p = f(q), equal masses
template <class F>
Moments moments(const Eigen::Matrix3Xd& q, F f) {
  Moments m{Eigen::Matrix3d::Zero(), 0.0};
  for (int i = 0; i < q.cols(); ++i) {
    m.a += f(Eigen::Vector3d(q.col(i))) * q.col(i).transpose();
    m.rest_moment += q.col(i).squaredNorm();
  }
  return m;
}

void expect_proper_rotation(const Eigen::Matrix3d& r) {
  ASSERT_TRUE(r.allFinite());
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
  EXPECT_LT((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 1e-12);
}

Eigen::Matrix3Xd solid_cluster() {
  Eigen::Matrix3Xd q(3, 6);
  q << 1, -1, 0.3, 0.2, -0.4, 0.1,   //
      0.2, 0.1, 2, -1.5, 0.3, -0.2,  //
      0.1, -0.3, 0.2, 0.4, 1.2, -1.0;
  return q;
}

TEST(RotationExtraction, RigidRotationIsRecovered) {
  const Eigen::Matrix3Xd q = solid_cluster();
  for (int seed = 1; seed <= 20; ++seed) {
    const Eigen::Matrix3d truth = random_rotation(seed);
    const Moments m = moments(q, [&](const Eigen::Vector3d& x) { return truth * x; });
    const Eigen::Matrix3d r = extract_rotation(m.a, Eigen::Matrix3d::Identity(), m.rest_moment);
    expect_proper_rotation(r);
    EXPECT_LT((r - truth).norm(), 1e-7) << "seed " << seed;
  }
}

TEST(RotationExtraction, HalfTurnFromAnIdentityWarmStart) {
  // a warm start exactly 180 deg away is a stationary point of iterative methods, not of the SVD
  const Eigen::Matrix3Xd q = solid_cluster();
  const Eigen::Matrix3d truth =
      Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Moments m = moments(q, [&](const Eigen::Vector3d& x) { return truth * x; });
  const Eigen::Matrix3d r = extract_rotation(m.a, Eigen::Matrix3d::Identity(), m.rest_moment);
  expect_proper_rotation(r);
  EXPECT_LT((r - truth).norm(), 1e-7);
}

TEST(RotationExtraction, InvertedClusterGivesAProperRotation) {
  const Eigen::Matrix3Xd q = solid_cluster();
  const Eigen::Matrix3d mirror = Eigen::Vector3d(1, 1, -1).asDiagonal();
  for (int seed = 1; seed <= 10; ++seed) {
    const Eigen::Matrix3d rot = random_rotation(seed);
    const Moments m = moments(q, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(rot * mirror * x); });
    ASSERT_LT(m.a.determinant(), 0.0) << "the cluster is inverted";
    const Eigen::Matrix3d r = extract_rotation(m.a, Eigen::Matrix3d::Identity(), m.rest_moment);
    expect_proper_rotation(r);
    // the best proper rotation: nothing in SO(3) matches the inverted cluster better
    const double best = (r.transpose() * m.a).trace();
    for (int t = 0; t < 50; ++t) EXPECT_LE((random_rotation(100 + t).transpose() * m.a).trace(), best + 1e-12);
  }
}

TEST(RotationExtraction, CoplanarClusterGivesTheTrueRotation) {
  Eigen::Matrix3Xd q(3, 4);
  q << 1, -1, 0, 0.5,   //
      0, 0.2, 1, -1.2,  //
      0, 0, 0, 0;
  const Eigen::Matrix3d truth = random_rotation(7);
  const Moments m = moments(q, [&](const Eigen::Vector3d& x) { return truth * x; });
  EXPECT_NEAR(m.a.determinant(), 0.0, 1e-12);
  const Eigen::Matrix3d r = extract_rotation(m.a, Eigen::Matrix3d::Identity(), m.rest_moment);
  expect_proper_rotation(r);
  EXPECT_LT((r - truth).norm(), 1e-7);
}

TEST(RotationExtraction, CollinearClusterAlignsTheLineAndKeepsThePreviousSpin) {
  Eigen::Matrix3Xd q(3, 3);
  q << -1, 0, 1,  //
      0, 0, 0,    //
      0, 0, 0;
  const Eigen::Matrix3d truth = random_rotation(3);
  const Moments m = moments(q, [&](const Eigen::Vector3d& x) { return truth * x; });
  // previous: the true rotation spun about the line; the line's spin is not in the data
  const Eigen::Matrix3d previous = truth * Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d r = extract_rotation(m.a, previous, m.rest_moment);
  expect_proper_rotation(r);
  EXPECT_LT((r * Eigen::Vector3d::UnitX() - truth * Eigen::Vector3d::UnitX()).norm(), 1e-7) << "line aligned";
  EXPECT_LT((r - previous).norm(), 1e-6) << "spin about the line taken from the previous frame";
}

TEST(RotationExtraction, CoincidentClusterKeepsThePreviousRotation) {
  const Eigen::Matrix3d previous = random_rotation(11);
  const Eigen::Matrix3d r = extract_rotation(Eigen::Matrix3d::Zero(), previous, 2.5);
  expect_proper_rotation(r);
  EXPECT_LT((r - previous).norm(), 1e-12);
  // a cluster with no rest extent either
  expect_proper_rotation(extract_rotation(Eigen::Matrix3d::Zero(), previous, 0.0));
}

TEST(RotationExtraction, NonFiniteInputKeepsThePreviousRotation) {
  const Eigen::Matrix3d previous = random_rotation(5);
  Eigen::Matrix3d a = Eigen::Matrix3d::Identity();
  a(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(extract_rotation(a, previous, 1.0), previous);
  a(1, 2) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(extract_rotation(a, previous, 1.0), previous);
}

// The SVD started from the right vectors a cluster's last solve found gives the cold start's R:
// a cluster stretched and turned a little more each solve (as between PBD iterations), inverted
// once on the way, then a non-finite moment (the start goes back to the identity)
TEST(RotationExtraction, AWarmStartedSvdGivesTheColdStartsRotation) {
  const Eigen::Matrix3Xd q = solid_cluster();
  Eigen::Matrix3d right = Eigen::Matrix3d::Identity(), previous_warm = Eigen::Matrix3d::Identity(),
                  previous_cold = Eigen::Matrix3d::Identity();
  double worst = 0.0;
  Eigen::Matrix3d last_a;
  for (int k = 0; k < 200; ++k) {
    const double s = 0.01 * k;
    Eigen::Matrix3d f = Eigen::AngleAxisd(s, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() *
                        Eigen::Vector3d(1.0 + 0.5 * std::sin(s), 1.0 - 0.3 * s / 2.0, 0.8 + 0.1 * s).asDiagonal();
    if (k == 150) f.col(2) = -f.col(2);  // inverted: det R stays +1
    const Moments m = moments(q, [&](const Eigen::Vector3d& x) -> Eigen::Vector3d { return f * x; });
    last_a = m.a;
    previous_warm = extract_rotation(m.a, previous_warm, m.rest_moment, &right);
    previous_cold = extract_rotation(m.a, previous_cold, m.rest_moment);
    expect_proper_rotation(previous_warm);
    worst = std::max(worst, (previous_warm - previous_cold).cwiseAbs().maxCoeff());
    EXPECT_LT((right.transpose() * right - Eigen::Matrix3d::Identity()).norm(), 1e-12) << "the start stays orthonormal";
  }
  EXPECT_LT(worst, 1e-13);
  // what is kept is the last solve's right singular vectors: they diagonalise A^T A
  const Eigen::Matrix3d d = right.transpose() * last_a.transpose() * last_a * right;
  EXPECT_LT((d - Eigen::Matrix3d(d.diagonal().asDiagonal())).norm(), 1e-10 * d.norm());
  EXPECT_GT((right.cwiseAbs() - Eigen::Matrix3d::Identity()).norm(), 0.1) << "not the cold start's identity";
  // a start that is no orthonormal basis (none, not finite, two columns alike) gives the cold
  // start's rotation and leaves an orthonormal one behind
  const Eigen::Matrix3d turn = random_rotation(4);
  const Moments m = moments(q, [&](const Eigen::Vector3d& x) -> Eigen::Vector3d { return turn * x; });
  const Eigen::Matrix3d cold = extract_rotation(m.a, Eigen::Matrix3d::Identity(), m.rest_moment);
  Eigen::Matrix3d alike = Eigen::Matrix3d::Identity();
  alike.col(1) = alike.col(0);
  for (Eigen::Matrix3d bad :
       {Eigen::Matrix3d(Eigen::Matrix3d::Zero()),
        Eigen::Matrix3d(Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN())), alike}) {
    const Eigen::Matrix3d r = extract_rotation(m.a, Eigen::Matrix3d::Identity(), m.rest_moment, &bad);
    EXPECT_LT((r - cold).cwiseAbs().maxCoeff(), 1e-13);
    EXPECT_LT((bad.transpose() * bad - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  }
  Eigen::Matrix3d a = Eigen::Matrix3d::Identity();
  a(0, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(extract_rotation(a, previous_warm, 1.0, &right), previous_warm);
  EXPECT_EQ(right, Eigen::Matrix3d::Identity()) << "a failed solve leaves no start behind";
}

}  // namespace
}  // namespace pcisim::physics::pbd
