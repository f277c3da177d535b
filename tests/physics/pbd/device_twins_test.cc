// The device arithmetic of the CUDA Jacobi solver (device_constraints.h, device_rotation.h), run
// on the host against the Eigen originals it twins. Runs without a GPU. Tolerances: the
// projections repeat the same operations (differences only where the compiler reorders, 1e-15
// relative); the rotation comes from a different SVD (one-sided Jacobi vs Eigen's two-sided
// JacobiSVD), so it agrees to 1e-12 per entry on full-rank and inverted matrices.
#include <gtest/gtest.h>

#include <Eigen/SVD>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cstdio>
#include <random>

#include "physics/pbd/device_constraints.h"
#include "physics/pbd/device_rotation.h"
#include "physics/pbd/dihedral_bending_constraint.h"
#include "physics/pbd/distance_constraint.h"
#include "physics/pbd/rotation_extraction.h"
#include "physics/pbd/shape_matching_clusters.h"

namespace pcisim::physics::pbd {
namespace {

device::Vec3 to_dev(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}
Eigen::Vector3d to_eigen(device::Vec3 v) {
  return {v.x, v.y, v.z};
}
device::Mat3 to_dev(const Eigen::Matrix3d& m) {
  device::Mat3 r;
  for (int k = 0; k < 9; ++k) r.m[k] = m.data()[k];
  return r;
}
Eigen::Matrix3d to_eigen(const device::Mat3& m) {
  return Eigen::Map<const Eigen::Matrix3d>(m.m);
}

TEST(DeviceTwins, ProjectionsMatchTheEigenOriginals) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  auto rv = [&] { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  for (int trial = 0; trial < 500; ++trial) {
    const Eigen::Vector3d xi = rv(), xj = rv();
    double dl = 0, ddl = 0;
    Eigen::Vector3d dxi = Eigen::Vector3d::Zero(), dxj = Eigen::Vector3d::Zero();
    device::Vec3 gxi, gxj;
    const bool a = project_distance(xi, xj, 1000.0, 500.0, 0.004, 2e-3 * 900.0, 1e-4, &dl, &dxi, &dxj);
    const bool b =
        device::project_distance(to_dev(xi), to_dev(xj), 1000.0, 500.0, 0.004, 2e-3 * 900.0, 1e-4, &ddl, &gxi, &gxj);
    ASSERT_EQ(a, b);
    EXPECT_NEAR(dl, ddl, 1e-15 * std::abs(dl) + 1e-30);
    EXPECT_LE((dxi - to_eigen(gxi)).norm(), 1e-15 * dxi.norm() + 1e-30);
    EXPECT_LE((dxj - to_eigen(gxj)).norm(), 1e-15 * dxj.norm() + 1e-30);

    Eigen::Vector3d xs[4] = {rv(), rv(), rv(), rv()}, dx[4];
    device::Vec3 gs[4], gdx[4];
    for (int k = 0; k < 4; ++k) gs[k] = to_dev(xs[k]);
    const double w[4] = {1000.0, 1000.0, 0.0, 2000.0};
    const bool c = project_dihedral_bending(xs, w, 0.3, 0.5, 0.01, &dl, dx);
    const bool d = device::project_dihedral_bending(gs, w, 0.3, 0.5, 0.01, &ddl, gdx);
    ASSERT_EQ(c, d);
    if (c) {
      EXPECT_NEAR(dl, ddl, 1e-13 * std::abs(dl) + 1e-30);
      for (int k = 0; k < 4; ++k) EXPECT_LE((dx[k] - to_eigen(gdx[k])).norm(), 1e-13 * dx[k].norm() + 1e-30);
    }

    Eigen::Vector3d gl, gdx2;
    device::Vec3 dgl, dgdx;
    const Eigen::Vector3d lam = rv();
    ASSERT_TRUE(project_to_goal(xi, xj, 1000.0, 0.001, 1e-4, 1.0 / 60.0, lam, &gl, &gdx2));
    ASSERT_TRUE(
        device::project_to_goal(to_dev(xi), to_dev(xj), 1000.0, 0.001, 1e-4, 1.0 / 60.0, to_dev(lam), &dgl, &dgdx));
    EXPECT_LE((gl - to_eigen(dgl)).norm(), 1e-15 * gl.norm() + 1e-30);
    EXPECT_LE((gdx2 - to_eigen(dgdx)).norm(), 1e-15 * gdx2.norm() + 1e-30);
  }
}

// the reference: Eigen's JacobiSVD of A + s R_prev with the reflection fix on the thinnest axis
// (what extract_rotation computed before it ran the twin's kernel on the CPU too)
Eigen::Matrix3d eigen_svd_rotation(const Eigen::Matrix3d& a, const Eigen::Matrix3d& previous, double rest_moment) {
  const Eigen::Matrix3d m = a + std::max(kRotationRegularisation * rest_moment, 1e-300) * previous;
  if (!m.allFinite()) return previous;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) = -u.col(2);
  return u * svd.matrixV().transpose();
}

TEST(DeviceTwins, RotationMatchesEigenSvdIncludingInvertedClusters) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Matrix3d a;
    for (int k = 0; k < 9; ++k) a.data()[k] = g(rng);
    if (trial % 3 == 1) a.col(0) = -a.col(0);  // mirrored: det < 0
    if (trial % 3 == 2)
      a = Eigen::AngleAxisd(g(rng), Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized()).toRotationMatrix() *
          Eigen::Vector3d(3.0, 2.0, 0.5).asDiagonal();  // a rotated, stretched cluster
    const Eigen::Matrix3d prev = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Matrix3d cpu = eigen_svd_rotation(a, prev, 5.0);
    const Eigen::Matrix3d gpu = to_eigen(device::extract_rotation(to_dev(a), to_dev(prev), 5.0));
    ASSERT_EQ(extract_rotation(a, prev, 5.0), gpu) << "the CPU path runs the same kernel";
    ASSERT_NEAR(gpu.determinant(), 1.0, 1e-12) << "trial " << trial;
    ASSERT_LE((gpu.transpose() * gpu - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
    worst = std::max(worst, (cpu - gpu).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, 1e-12);
  std::printf("[ measured ] rotation twin vs Eigen JacobiSVD: worst entry difference %.3g\n", worst);
}

TEST(DeviceTwins, RotationOfDegenerateClustersStaysProperAndNearTheCpu) {
  const Eigen::Matrix3d prev = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  // coplanar (rank 2), collinear (rank 1), coincident (zero), non-finite
  Eigen::Matrix3d planar = Eigen::Matrix3d::Zero(), line = Eigen::Matrix3d::Zero();
  planar(0, 0) = 2.0, planar(1, 1) = 1.0;
  line(0, 0) = 2.0;
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(1, 2) = std::nan("");
  for (const Eigen::Matrix3d& a : {planar, line, Eigen::Matrix3d::Zero().eval(), nan}) {
    const Eigen::Matrix3d cpu = eigen_svd_rotation(a, prev, 5.0);
    const Eigen::Matrix3d gpu = to_eigen(device::extract_rotation(to_dev(a), to_dev(prev), 5.0));
    ASSERT_TRUE(gpu.allFinite());
    EXPECT_NEAR(gpu.determinant(), 1.0, 1e-9);
    // rank <= 1: the free axes come from the 1e-9 regulariser, good to ~1e-7 (see device_rotation.h)
    EXPECT_LE((cpu - gpu).cwiseAbs().maxCoeff(), 1e-6) << a;
  }
}

}  // namespace
}  // namespace pcisim::physics::pbd
