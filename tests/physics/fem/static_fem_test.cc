// The reference FEM against what it must reproduce exactly: its stress and stiffness are the
// derivatives of its energy (finite differences), and a neo-Hookean block stretched or squeezed
// along one axis with free sides matches the analytic answer (homogeneous deformation: linear
// tets represent it exactly, so the comparison is to solver tolerance, not to mesh error).
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <random>

#include "anatomy/mesh/kuhn_tetrahedra.h"
#include "physics/fem/static_fem.h"

namespace pcisim::physics::fem {
namespace {

// a block of nx x ny x nz cubes of edge h (m), each cut into Kuhn's six tets
FemMesh block(int nx, int ny, int nz, double h) {
  FemMesh m;
  auto id = [&](int i, int j, int k) { return i + (nx + 1) * (j + (ny + 1) * k); };
  m.rest_m.resize(3, (nx + 1) * (ny + 1) * (nz + 1));
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) m.rest_m.col(id(i, j, k)) = h * Eigen::Vector3d(i, j, k);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& t : anatomy::kKuhnTetrahedra) {
          std::array<int, 4> tet{};
          for (int v = 0; v < 4; ++v) tet[v] = id(i + (t[v] & 1), j + ((t[v] >> 1) & 1), k + ((t[v] >> 2) & 1));
          m.tets.push_back(tet);
        }
  return m;
}

const NeoHookean kTissue = neo_hookean_from_young(5e3, 0.45);  // a soft organ's order of magnitude

TEST(NeoHookean, StressAndItsDifferentialAreTheEnergysDerivatives) {
  EXPECT_NEAR(kTissue.mu_pa, 5e3 / 2.9, 1e-9);
  EXPECT_NEAR(kTissue.lambda_pa, 5e3 * 0.45 / (1.45 * 0.1), 1e-6);
  EXPECT_EQ(energy_density(kTissue, Eigen::Matrix3d::Identity()), 0.0);
  EXPECT_LT(first_piola(kTissue, Eigen::Matrix3d::Identity()).norm(), 1e-9);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::Matrix3d f = Eigen::Matrix3d::Identity(), df;
    for (int k = 0; k < 9; ++k) f.data()[k] += u(rng), df.data()[k] = u(rng);
    ASSERT_GT(f.determinant(), 0.0);
    const double eps = 1e-6;
    const Eigen::Matrix3d p = first_piola(kTissue, f);
    // dpsi = P : dF, and dP against central differences of P
    const double dpsi = (energy_density(kTissue, f + eps * df) - energy_density(kTissue, f - eps * df)) / (2 * eps);
    EXPECT_NEAR(dpsi, (p.array() * df.array()).sum(), 1e-6 * std::max(1.0, std::abs(dpsi)));
    const Eigen::Matrix3d dp_fd = (first_piola(kTissue, f + eps * df) - first_piola(kTissue, f - eps * df)) / (2 * eps);
    EXPECT_LT((first_piola_differential(kTissue, f, df) - dp_fd).norm(), 1e-5 * std::max(1.0, dp_fd.norm()));
  }
  EXPECT_TRUE(std::isinf(energy_density(kTissue, -Eigen::Matrix3d::Identity())));
  EXPECT_THROW(neo_hookean_from_young(5e3, 0.5), std::invalid_argument);
  EXPECT_THROW(neo_hookean_from_young(0.0, 0.3), std::invalid_argument);
}

TEST(StaticFem, GradientAndStiffnessAreTheEnergysDerivatives) {
  const StaticFem fem(block(2, 1, 2, 0.01), kTissue);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  Eigen::VectorXd x = fem.rest_positions();
  for (int i = 0; i < x.size(); ++i) x[i] += u(rng);
  Eigen::VectorXd g, g_plus, g_minus;
  fem.gradient(x, &g);
  Eigen::SparseMatrix<double> k;
  fem.stiffness(x, &k);
  const Eigen::MatrixXd kd(k);
  EXPECT_LT((kd - kd.transpose()).cwiseAbs().maxCoeff(), 1e-9 * kd.cwiseAbs().maxCoeff()) << "symmetric";
  const double eps = 1e-7;
  double worst_g = 0, worst_k = 0;
  for (int i = 0; i < x.size(); ++i) {
    Eigen::VectorXd xp = x, xm = x;
    xp[i] += eps, xm[i] -= eps;
    worst_g = std::max(worst_g, std::abs((fem.energy(xp) - fem.energy(xm)) / (2 * eps) - g[i]));
    fem.gradient(xp, &g_plus);
    fem.gradient(xm, &g_minus);
    worst_k = std::max(worst_k, ((g_plus - g_minus) / (2 * eps) - kd.col(i)).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_g, 1e-6 * g.cwiseAbs().maxCoeff());
  EXPECT_LT(worst_k, 1e-5 * kd.cwiseAbs().maxCoeff());
}

// uniaxial: P_xx = 0 at the free sides gives mu (l^2 - 1) + lambda ln(a l^2) = 0 for the lateral
// stretch l; then P_zz = mu (a - 1/a) + lambda ln(a l^2) / a
double lateral_stretch(const NeoHookean& m, double a) {
  double lo = 1e-3, hi = 10.0;
  for (int i = 0; i < 200; ++i) {
    const double l = 0.5 * (lo + hi);
    (m.mu_pa * (l * l - 1) + m.lambda_pa * std::log(a * l * l) > 0 ? hi : lo) = l;
  }
  return 0.5 * (lo + hi);
}

TEST(StaticFem, UniaxialStretchAndCompressionMatchTheAnalyticAnswer) {
  constexpr double kEdge = 0.01;  // a 20 mm cube of 2 x 2 x 2 cells
  const StaticFem fem(block(2, 2, 2, kEdge), kTissue);
  const int n = fem.node_count();
  const double side = 2 * kEdge;
  for (double a : {1.3, 0.7}) {
    FemBoundary bc{std::vector<uint8_t>(3 * n, 0), fem.rest_positions()};
    // bottom z = 0 held in z, top moved to a * side in z; the rigid motions pinned at the origin
    // corner (x, y) and along its x edge (y)
    for (int v = 0; v < n; ++v) {
      const Eigen::Vector3d p = fem.mesh().rest_m.col(v);
      if (p.z() < 1e-12) bc.fixed[3 * v + 2] = 1;
      if (p.z() > side - 1e-12) bc.fixed[3 * v + 2] = 1, bc.target_m[3 * v + 2] = a * side;
      if (p.norm() < 1e-12) bc.fixed[3 * v] = bc.fixed[3 * v + 1] = 1;
      if (p.y() < 1e-12 && p.z() < 1e-12) bc.fixed[3 * v + 1] = 1;
    }
    Eigen::VectorXd x;
    FemSolveOptions opt;
    opt.force_tolerance_n = 1e-10;
    const FemSolveReport r = fem.solve(bc, &x, opt);
    ASSERT_TRUE(r.converged) << "residual " << r.residual_n;
    const double l = lateral_stretch(kTissue, a);
    // every node where the homogeneous deformation puts it
    double worst_m = 0;
    for (int v = 0; v < n; ++v) {
      const Eigen::Vector3d p = fem.mesh().rest_m.col(v);
      worst_m = std::max(worst_m, (x.segment<3>(3 * v) - Eigen::Vector3d(l * p.x(), l * p.y(), a * p.z())).norm());
    }
    EXPECT_LT(worst_m, 1e-9);
    // the top's reaction against P_zz times the rest area
    Eigen::VectorXd g;
    fem.gradient(x, &g);
    double reaction_n = 0;
    for (int v = 0; v < n; ++v)
      if (fem.mesh().rest_m(2, v) > side - 1e-12) reaction_n += g[3 * v + 2];
    const double p_zz = kTissue.mu_pa * (a - 1 / a) + kTissue.lambda_pa * std::log(a * l * l) / a;
    EXPECT_NEAR(reaction_n, p_zz * side * side, 1e-8 * std::abs(p_zz * side * side));
    std::printf("stretch %.1f: lateral %.6f (analytic %.6f), force %.6f N (analytic %.6f), %d Newton steps\n", a,
                x[3 * (n - 1)] / side, l, reaction_n, p_zz * side * side, r.newton_iterations);
  }
}

TEST(StaticFem, ADegenerateOrOutOfRangeTetIsRefused) {
  FemMesh flat = block(1, 1, 1, 0.01);
  flat.tets.push_back({0, 1, 2, 3});  // the four corners of the bottom face: coplanar
  EXPECT_THROW(StaticFem(flat, kTissue), std::invalid_argument);
  FemMesh bad = block(1, 1, 1, 0.01);
  bad.tets.push_back({0, 1, 2, 99});
  EXPECT_THROW(StaticFem(bad, kTissue), std::invalid_argument);
}

}  // namespace
}  // namespace pcisim::physics::fem
