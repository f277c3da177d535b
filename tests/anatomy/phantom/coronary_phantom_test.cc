#include "anatomy/phantom/coronary_phantom.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>

namespace pcisim::anatomy {
namespace {

const VesselBranch& branch(const VesselTree& tree, const char* name) {
  const int i = tree.find(name);
  EXPECT_GE(i, 0) << name;
  return tree.branches.at(i);
}

// unit direction of a branch over its first `mm` millimetres
Eigen::Vector3d start_direction(const VesselBranch& b, double mm) {
  const size_t k = std::min(b.points.size() - 1, static_cast<size_t>(mm / 0.5));
  return (b.points[k].position_m - b.points[0].position_m).normalized();
}

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

TEST(PhantomTest, SameSeedSameTreeOtherSeedOtherTree) {
  const VesselTree a = make_coronary_phantom({.seed = 5});
  const VesselTree b = make_coronary_phantom({.seed = 5});
  const VesselTree c = make_coronary_phantom({.seed = 6});
  ASSERT_EQ(a.branches.size(), b.branches.size());
  for (size_t i = 0; i < a.branches.size(); ++i) {
    ASSERT_EQ(a.branches[i].points.size(), b.branches[i].points.size());
    for (size_t k = 0; k < a.branches[i].points.size(); ++k) {
      EXPECT_EQ(a.branches[i].points[k].position_m, b.branches[i].points[k].position_m);
      EXPECT_EQ(a.branches[i].points[k].radius_m, b.branches[i].points[k].radius_m);
    }
  }
  const auto& lad_a = branch(a, "LAD").points.back().position_m;
  const auto& lad_c = branch(c, "LAD").points.back().position_m;
  EXPECT_GT((lad_a - lad_c).norm(), 1e-3) << "another seed should move the LAD's end by > 1 mm";
}

TEST(PhantomTest, HasTheNamedBranchesWithTheirParents) {
  const VesselTree t = make_coronary_phantom({});
  const char* names[] = {"aorta", "LM", "LAD", "LCx", "D1", "D2", "OM1", "OM2", "RCA"};
  for (const char* n : names) EXPECT_GE(t.find(n), 0) << n;
  EXPECT_EQ(t.find("nope"), -1);
  EXPECT_EQ(branch(t, "aorta").parent, -1);
  EXPECT_EQ(branch(t, "LM").parent, t.find("aorta"));
  EXPECT_EQ(branch(t, "RCA").parent, t.find("aorta"));
  EXPECT_EQ(branch(t, "LAD").parent, t.find("LM"));
  EXPECT_EQ(branch(t, "LCx").parent, t.find("LM"));
  EXPECT_EQ(branch(t, "D1").parent, t.find("LAD"));
  EXPECT_EQ(branch(t, "D2").parent, t.find("LAD"));
  EXPECT_EQ(branch(t, "OM1").parent, t.find("LCx"));
  EXPECT_EQ(branch(t, "OM2").parent, t.find("LCx"));
}

TEST(PhantomTest, ChildrenStartOnTheirParentsPoint) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const VesselTree t = make_coronary_phantom({.seed = seed});
    for (const auto& b : t.branches) {
      if (b.parent < 0) continue;
      const auto& parent = t.branches[b.parent];
      ASSERT_GE(b.parent_point, 0);
      ASSERT_LT(b.parent_point, static_cast<int>(parent.points.size()));
      EXPECT_LT((b.points.front().position_m - parent.points[b.parent_point].position_m).norm(), 1e-12)
          << b.name << " seed " << seed;
    }
  }
}

TEST(PhantomTest, DimensionsAreAdult) {
  for (uint32_t seed : {1u, 2u, 3u, 4u}) {
    const VesselTree t = make_coronary_phantom({.seed = seed});
    const auto& aorta = branch(t, "aorta");
    EXPECT_NEAR(aorta.points[0].radius_m, 14e-3, 1e-3);
    EXPECT_NEAR(branch_length_m(aorta), 60e-3, 5e-3);
    // the LM runs from the aortic centerline; ~10 mm of it lies outside the aortic wall
    const auto& lm = branch(t, "LM");
    EXPECT_NEAR(lm.points[0].radius_m, 2.0e-3, 0.15e-3);
    EXPECT_NEAR(branch_length_m(lm) - aorta.points[0].radius_m, 10e-3, 2e-3);
    struct Expect {
      const char* name;
      double length_m, r0_m, r1_m;
    };
    for (const Expect& e : {Expect{"LAD", 120e-3, 1.8e-3, 0.8e-3}, Expect{"LCx", 80e-3, 1.6e-3, 0.8e-3},
                            Expect{"RCA", 120e-3, 1.8e-3, 0.9e-3}}) {
      const auto& b = branch(t, e.name);
      EXPECT_NEAR(branch_length_m(b), e.length_m, 0.1 * e.length_m) << e.name;
      EXPECT_NEAR(b.points.front().radius_m, e.r0_m, 0.1e-3) << e.name;
      EXPECT_NEAR(b.points.back().radius_m, e.r1_m, 0.1e-3) << e.name;
    }
    for (const char* name : {"D1", "D2", "OM1", "OM2"}) {
      const auto& b = branch(t, name);
      EXPECT_LE(b.points.front().radius_m, 1.0e-3) << name;
      EXPECT_LT(b.points.back().radius_m, 0.8e-3) << name;
      EXPECT_GT(branch_length_m(b), 30e-3) << name;
    }
    for (const auto& b : t.branches) {
      for (size_t k = 1; k < b.points.size(); ++k) {
        const double step = (b.points[k].position_m - b.points[k - 1].position_m).norm();
        EXPECT_NEAR(step, 0.5e-3, 0.05e-3) << b.name << " point " << k;
      }
    }
  }
}

TEST(PhantomTest, BranchesTouchOnlyWhereTheyJoin) {
  for (uint32_t seed : {1u, 2u, 3u, 4u, 5u}) {
    const VesselTree t = make_coronary_phantom({.seed = seed});
    for (size_t i = 0; i < t.branches.size(); ++i) {
      for (size_t j = i + 1; j < t.branches.size(); ++j) {
        const auto& a = t.branches[i];
        const auto& b = t.branches[j];
        double gap_m = 1.0;
        for (size_t ka = 0; ka < a.points.size(); ++ka) {
          for (size_t kb = 0; kb < b.points.size(); ++kb) {
            // leave out 8 mm about a junction (parent and child, or two daughters of one parent)
            if (b.parent == static_cast<int>(i) && std::abs(static_cast<int>(ka) - b.parent_point) < 16 && kb < 16)
              continue;
            if (a.parent == b.parent && ka < 16 && kb < 16) continue;
            // the LM and RCA start on the aortic centerline: their first ~16 mm run inside it
            if (a.name == "aorta" && b.parent == static_cast<int>(i) && kb < 36) continue;
            const double gap = (a.points[ka].position_m - b.points[kb].position_m).norm() - a.points[ka].radius_m -
                               b.points[kb].radius_m;
            gap_m = std::min(gap_m, gap);
          }
        }
        EXPECT_GT(gap_m, 0.5e-3) << a.name << " and " << b.name << ", seed " << seed;
      }
    }
  }
}

TEST(PhantomTest, LeftMainForksIntoClearlyDifferentDirections) {
  for (uint32_t seed : {1u, 2u, 3u, 4u, 5u}) {
    const VesselTree t = make_coronary_phantom({.seed = seed});
    const auto& lm = branch(t, "LM");
    const auto& lad = branch(t, "LAD");
    const auto& lcx = branch(t, "LCx");
    EXPECT_EQ(lad.parent_point, static_cast<int>(lm.points.size()) - 1);
    EXPECT_EQ(lcx.parent_point, static_cast<int>(lm.points.size()) - 1);
    const double fork = angle_deg(start_direction(lad, 3.0), start_direction(lcx, 3.0));
    EXPECT_GT(fork, 60.0) << "seed " << seed;
    EXPECT_LT(fork, 90.0) << "seed " << seed;
    // neither daughter doubles back into the LM
    const Eigen::Vector3d lm_dir = start_direction(lm, 20.0);
    EXPECT_LT(angle_deg(lm_dir, start_direction(lad, 3.0)), 80.0);
    EXPECT_LT(angle_deg(lm_dir, start_direction(lcx, 3.0)), 80.0);
  }
}

TEST(PhantomTest, MainBranchesAreCurvedOutOfPlaneAndFollowable) {
  const VesselTree t = make_coronary_phantom({});
  for (const char* name : {"LAD", "LCx", "RCA"}) {
    const auto& b = branch(t, name);
    // deviation from the best-fit plane: a planar curve would give ~0
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : b.points) mean += p.position_m;
    mean /= b.points.size();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : b.points) cov += (p.position_m - mean) * (p.position_m - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Eigen::Vector3d normal = eig.eigenvectors().col(0);
    double off_plane = 0.0;
    for (const auto& p : b.points) off_plane = std::max(off_plane, std::abs((p.position_m - mean).dot(normal)));
    EXPECT_GT(off_plane, 2e-3) << name;
    // curved (chord well below length) but no kink sharper than a 8 mm radius
    EXPECT_LT((b.points.back().position_m - b.points.front().position_m).norm(), 0.9 * branch_length_m(b));
    for (size_t k = 1; k + 1 < b.points.size(); ++k) {
      const Eigen::Vector3d a = b.points[k].position_m - b.points[k - 1].position_m;
      const Eigen::Vector3d c = b.points[k + 1].position_m - b.points[k].position_m;
      const double turn_rad = angle_deg(a, c) * std::numbers::pi / 180.0;
      EXPECT_LT(turn_rad, 0.5e-3 / 8e-3) << name << " point " << k;
    }
  }
}

TEST(PhantomTest, GuideCatheterEndsOnTheLeftMainInsideTheAorta) {
  const VesselTree t = make_coronary_phantom({});
  const auto path = guide_catheter_path(t);
  ASSERT_GT(path.size(), 20u);
  const auto& lm = branch(t, "LM");
  EXPECT_EQ(path.back(), lm.points.front().position_m);
  for (size_t k = 1; k < path.size(); ++k) {
    EXPECT_NEAR((path[k] - path[k - 1]).norm(), 0.5e-3, 0.05e-3) << k;
  }
  // it arrives along the LM, so the wire leaves it straight into the LM
  const Eigen::Vector3d arrive = (path.back() - path[path.size() - 5]).normalized();
  EXPECT_LT(angle_deg(arrive, start_direction(lm, 5.0)), 10.0);
  // and it stays inside the aorta, clear of its wall by a 2 mm catheter radius
  const auto& aorta = branch(t, "aorta");
  for (const auto& p : path) {
    double d_m = 0;
    const int b = nearest_branch(VesselTree{{aorta}}, p, &d_m);
    EXPECT_EQ(b, 0);
    EXPECT_LT(d_m, aorta.points[0].radius_m - 2e-3);
  }
  EXPECT_TRUE(guide_catheter_path(VesselTree{}).empty());
}

TEST(PhantomTest, NearestBranchFindsTheBranchUnderAPoint) {
  const VesselTree t = make_coronary_phantom({});
  for (const char* name : {"LAD", "LCx", "D1", "OM2", "RCA"}) {
    const auto& b = branch(t, name);
    const Eigen::Vector3d p = b.points[b.points.size() * 3 / 4].position_m;
    double d_m = -1;
    EXPECT_EQ(nearest_branch(t, p, &d_m), t.find(name));
    EXPECT_NEAR(d_m, 0.0, 1e-12);
  }
  // a child's first point lies on its parent's centerline: the tie goes to the parent
  const auto& lm = branch(t, "LM");
  EXPECT_EQ(nearest_branch(t, lm.points.front().position_m), t.find("aorta"));
  EXPECT_EQ(nearest_branch(t, lm.points[10].position_m), t.find("LM"));
  double d_m = 0;
  EXPECT_EQ(nearest_branch(VesselTree{}, Eigen::Vector3d::Zero(), &d_m), -1);
  EXPECT_TRUE(std::isinf(d_m));
  EXPECT_EQ(nearest_branch(t, Eigen::Vector3d::Constant(NAN), &d_m), -1);
}

}  // namespace
}  // namespace pcisim::anatomy
