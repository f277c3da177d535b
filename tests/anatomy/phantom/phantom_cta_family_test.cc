// The varied phantom family (issue #30): each variation it promises is drawn somewhere in a few
// seeds, lands where its facts say, and shows in the voxels as it should.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "anatomy/phantom/phantom_cta.h"
#include "anatomy/phantom/thorax_phantom.h"
#include "tests/anatomy/phantom/phantom_cta_probe.h"

namespace pcisim::anatomy {
namespace {

using Eigen::Vector3d;

// geometry and facts only: the family's anatomy on coarse voxels over a 140 mm field
PhantomCtaSpec coarse(uint32_t seed) {
  PhantomCtaSpec s = family_phantom_cta_spec(seed);
  s.dims = {10, 10, 10};
  s.spacing_mm = {14, 14, 14};
  s.direction = Eigen::Matrix3d::Identity();
  return s;
}

// the family's anatomy at 0.5 mm over a 130 mm field (the heart and its vessels), little noise
PhantomCtaSpec fine(uint32_t seed) {
  PhantomCtaSpec s = family_phantom_cta_spec(seed);
  s.dims = {260, 260, 260};
  s.spacing_mm = {0.5, 0.5, 0.5};
  s.noise_sigma_hu = 10;
  s.blur_sigma_mm = 0.4;
  s.direction = Eigen::Matrix3d::Identity();
  return s;
}

double min_distance_mm(const std::vector<Vector3d>& a, const VesselBranch& b) {
  double best = 1e300;
  for (const auto& p : a) {
    for (const auto& q : b.points) best = std::min(best, (p - q.position_m * 1e3).norm() - q.radius_m * 1e3);
  }
  return best;
}

TEST(PhantomCtaFamily, ScansCoverTheProtocolRanges) {
  double thinnest = 1, thickest = 0, most_anisotropic = 0, quietest = 100, noisiest = 0;
  std::set<double> directions;
  for (uint32_t seed = 1; seed <= 200; ++seed) {
    const PhantomCtaSpec s = family_phantom_cta_spec(seed);
    EXPECT_TRUE(s.family);
    EXPECT_EQ(s.seed, seed);
    EXPECT_EQ(s.spacing_mm.x(), s.spacing_mm.y());
    for (int a = 0; a < 3; ++a) {
      thinnest = std::min(thinnest, s.spacing_mm[a]);
      thickest = std::max(thickest, s.spacing_mm[a]);
      // the field holds the heart and its vessels: at least 140 mm each way
      EXPECT_GE(static_cast<double>(s.dims[a]) * s.spacing_mm[a], 140.0) << seed;
    }
    EXPECT_GE(static_cast<double>(s.dims[0]) * s.spacing_mm[0], 175.0) << seed;
    EXPECT_LE(s.dims[0] * s.dims[1] * s.dims[2], kMaxPhantomCtaVoxels);
    most_anisotropic = std::max(most_anisotropic, std::abs(s.spacing_mm.z() - s.spacing_mm.x()));
    quietest = std::min(quietest, s.noise_sigma_hu);
    noisiest = std::max(noisiest, s.noise_sigma_hu);
    EXPECT_GE(s.blur_sigma_mm, 0.3);
    EXPECT_LE(s.blur_sigma_mm, 0.6);
    directions.insert(s.direction(2, 2));
  }
  EXPECT_GE(thinnest, 0.3);
  EXPECT_LT(thinnest, 0.32);
  EXPECT_LE(thickest, 0.8);
  EXPECT_GT(thickest, 0.78);
  EXPECT_GT(most_anisotropic, 0.4);
  EXPECT_GE(quietest, 15);
  EXPECT_LT(quietest, 17);
  EXPECT_LE(noisiest, 45);
  EXPECT_GT(noisiest, 43);
  EXPECT_EQ(directions.size(), 2u);  // head-first and feet-first
  // the same seed, the same spec
  EXPECT_EQ(family_phantom_cta_spec(7).spacing_mm, family_phantom_cta_spec(7).spacing_mm);
}

TEST(PhantomCtaFamily, EachVariationIsDrawnSomewhere) {
  int open = 0, closed = 0, stents = 0, appendages = 0, crossing = 0, tortuous = 0;
  double narrowest = 180, widest = 0, thinnest_wall = 10, thickest_wall = 0, least_myo = 1e9, most_myo = 0;
  double least_rv = 1e9, most_rv = 0;
  for (uint32_t seed = 1; seed <= 16; ++seed) {
    const PhantomCta c = make_phantom_cta(coarse(seed));
    const auto& f = c.facts;
    ASSERT_TRUE(f.family);
    (f.open_valve ? open : closed)++;
    stents += !f.stent_branch.empty();
    appendages += f.laa_gap_mm >= 0;
    crossing += !f.crossing_veins.empty();
    tortuous += !f.tortuous_branch.empty();
    narrowest = std::min(narrowest, f.lad_lcx_angle_deg);
    widest = std::max(widest, f.lad_lcx_angle_deg);
    thinnest_wall = std::min(thinnest_wall, f.rv_wall_mm);
    thickest_wall = std::max(thickest_wall, f.rv_wall_mm);
    least_myo = std::min(least_myo, f.myocardium_hu);
    most_myo = std::max(most_myo, f.myocardium_hu);
    least_rv = std::min(least_rv, f.rv_hu);
    most_rv = std::max(most_rv, f.rv_hu);
    EXPECT_GE(f.heart_axes_scale.minCoeff(), 0.9);
    EXPECT_LE(f.heart_axes_scale.maxCoeff(), 1.1);
    EXPECT_NE(f.heart_axes_scale, Vector3d::Ones());
    // the small side branches are in the truth, start on their parent's point and end at 0.5 mm
    // (or at their start's radius where that is smaller)
    ASSERT_GE(f.side_branches.size(), 2u) << seed;
    for (const auto& name : f.side_branches) {
      const int b = c.truth.find(name);
      if (b < 0) continue;  // cut off by the field (facts.clipped_branches)
      const auto& br = c.truth.branches[b];
      const auto& parent = c.truth.branches[br.parent].points[br.parent_point];
      EXPECT_LT((br.points.front().position_m - parent.position_m).norm(), 1e-9) << name;
      if (std::find(f.clipped_branches.begin(), f.clipped_branches.end(), name) == f.clipped_branches.end())
        EXPECT_NEAR(br.points.back().radius_m, std::min(0.5e-3, br.points.front().radius_m), 1e-9) << name;
      EXPECT_LE(br.points.front().radius_m, 0.8e-3 + 1e-9) << name;
    }
    // the appendage never overlaps a lumen and lies beside the LCx
    if (f.laa_gap_mm >= 0) {
      EXPECT_GE(f.laa_gap_mm, 0.4);
      const Vector3d axis = f.laa_base_mm - f.laa_tip_mm;
      EXPECT_LT(min_distance_mm({f.laa_tip_mm - axis.normalized() * f.laa_tip_radius_mm}, branch(c, "LCx")), 2.5 + 0.1)
          << seed;
    }
    // a crossing vein touches the artery it crosses (its centre ra + rv above the artery's)
    for (const auto& v : f.crossing_veins) {
      EXPECT_GE(v.hu, 150);
      EXPECT_LE(v.hu, 300);
      EXPECT_GE(v.angle_deg, 45);
      EXPECT_LE(v.angle_deg, 90);
      const int b = c.truth.find(v.crosses);
      if (b < 0) continue;
      const double gap = min_distance_mm(v.points_mm, c.truth.branches[b]) - v.radius_mm;
      EXPECT_GT(gap, -0.2) << seed << " " << v.crosses;
      EXPECT_LT(gap, 0.3) << seed << " " << v.crosses;
    }
  }
  EXPECT_GT(open, 0);
  EXPECT_GT(closed, 0);
  EXPECT_GT(stents, 0);
  EXPECT_GT(appendages, 8);
  EXPECT_GT(crossing, 8);
  EXPECT_GT(tortuous, 0);
  EXPECT_LT(narrowest, 65);  // drawn over 36..112 deg; turned less where the trees would meet
  EXPECT_GT(widest, 90);
  EXPECT_LT(thinnest_wall, 2.6);
  EXPECT_GT(thickest_wall, 4.4);
  EXPECT_LT(least_myo, 70);
  EXPECT_GT(most_myo, 120);
  EXPECT_LT(least_rv, 100);  // unenhanced right heart (a saline chaser)
  EXPECT_GT(most_rv, 300);
  // the classic phantoms draw none of it
  PhantomCtaSpec classic = coarse(3);
  classic.family = false;
  const PhantomCta c = make_phantom_cta(classic);
  EXPECT_FALSE(c.facts.family);
  EXPECT_TRUE(c.facts.side_branches.empty() && c.facts.crossing_veins.empty() && c.facts.stent_branch.empty());
  EXPECT_LT(c.facts.laa_gap_mm, 0);
  EXPECT_EQ(c.facts.heart_axes_scale, Vector3d::Ones());
}

// the tortuous trunk has >= 3 bends of >= 45 deg (Li et al.'s definition), measured on its true
// centerline: over successive half wavelengths of its sine, the direction turns by >= 45 deg
// between two points half a wavelength apart at least three times
TEST(PhantomCtaFamily, ATortuousTrunkTurnsByMoreThan45DegreesBetweenBends) {
  for (uint32_t seed = 1; seed <= 40; ++seed) {
    const PhantomCta c = make_phantom_cta(coarse(seed));
    if (c.facts.tortuous_branch.empty()) continue;
    for (const auto& t : c.facts.tortuosity) {
      if (t.branch != c.facts.tortuous_branch) continue;
      const double turn_deg = 2 * std::atan(2 * M_PI * t.amplitude_mm / t.wavelength_mm) * 180 / M_PI;
      EXPECT_GE(turn_deg, 45.0) << seed;
      // curvature A (2 pi / wavelength)^2 under 1/8 mm^-1: a wire can follow it
      EXPECT_LT(t.amplitude_mm * std::pow(2 * M_PI / t.wavelength_mm, 2), 1.0 / 8.0) << seed;
      // on the centerline: the tangent over +-1 mm, compared half a wavelength on
      const auto& pts = branch(c, t.branch).points;
      const auto arc = arcs_mm(branch(c, t.branch));
      auto tangent_at = [&](double s) {
        auto at = [&](double x) {
          const size_t i = std::min<size_t>(std::lower_bound(arc.begin(), arc.end(), x) - arc.begin(), pts.size() - 1);
          return Vector3d(pts[i].position_m * 1e3);
        };
        return Vector3d((at(s + 1) - at(s - 1)).normalized());
      };
      const double half = 0.5 * t.wavelength_mm, start = c.facts.tortuous_branch == "RCA" ? 30.0 : 12.0;
      int bends = 0;
      for (double w = start; w + 2 * half + 1 < arc.back(); w += half) {
        double most = 0;
        for (double s = w; s < w + half; s += 0.5)
          most = std::max(most, std::acos(std::clamp(tangent_at(s).dot(tangent_at(s + half)), -1.0, 1.0)) * 180 / M_PI);
        bends += most >= 45.0;
      }
      std::printf("seed %u: %s, wavelength %.1f mm, amplitude %.2f mm: %d windows turning >= 45 deg\n", seed,
                  t.branch.c_str(), t.wavelength_mm, t.amplitude_mm, bends);
      EXPECT_GE(bends, 3) << seed;
      return;
    }
  }
  FAIL() << "no tortuous trunk in 40 seeds";
}

// the voxels: a stent's struts are metal at the lumen's wall (>= 1500 HU), its lumen stays
// contrast; calcium blooms past its edge; the appendage is left-atrial blood beside the LCx
TEST(PhantomCtaFamily, StentBloomAndAppendageInTheVoxels) {
  bool stent_seen = false, bloom_seen = false, laa_seen = false;
  for (uint32_t seed = 1; seed <= 12 && !(stent_seen && bloom_seen && laa_seen); ++seed) {
    const PhantomCtaFacts f = make_phantom_cta(coarse(seed)).facts;
    const bool want_stent = !stent_seen && !f.stent_branch.empty(), want_laa = !laa_seen && f.laa_gap_mm >= 0;
    if (!want_stent && !want_laa && bloom_seen) continue;
    const PhantomCta c = make_phantom_cta(fine(seed));
    auto inside = [&](const Vector3d& p) { return in_grid(c.ct, c.ct.physical_to_index(p)); };
    if (want_stent && inside(f.stent_center_mm)) {
      // the brightest voxel within 3 mm of the stent's centre, and the lumen on its axis
      const Vector3d ijk = c.ct.physical_to_index(f.stent_center_mm);
      double brightest = -1e9;
      for (int dz = -6; dz <= 6; ++dz) {
        for (int dy = -6; dy <= 6; ++dy) {
          for (int dx = -6; dx <= 6; ++dx) {
            const Vector3d q(std::round(ijk.x()) + dx, std::round(ijk.y()) + dy, std::round(ijk.z()) + dz);
            if (!in_grid(c.ct, q)) continue;
            brightest =
                std::max(brightest, static_cast<double>(c.ct.hu(int64_t(q.x()), int64_t(q.y()), int64_t(q.z()))));
          }
        }
      }
      const double axis = hu_at(c.ct, f.stent_center_mm);
      std::printf("seed %u: stent on %s, brightest %.0f HU, on its axis %.0f\n", seed, f.stent_branch.c_str(),
                  brightest, axis);
      EXPECT_GE(brightest, 1500) << seed;
      EXPECT_LT(axis, 0.7 * brightest) << seed;  // the struts at the wall, not across the lumen
      EXPECT_GT(axis, 150) << seed;
      stent_seen = true;
    }
    if (!bloom_seen) {
      // just outside each plaque along its radial axis (away from the lumen), half the bloom's
      // width past its edge: brighter with the bloom than in the same phantom without it
      PhantomCtaSpec plain = fine(seed);
      plain.calcium_blooming = false;
      const PhantomCta p = make_phantom_cta(plain);
      for (const auto& pl : c.facts.plaques) {
        const auto& b = branch(c, pl.branch);
        const auto arc = arcs_mm(b);
        const size_t i = std::lower_bound(arc.begin(), arc.end(), pl.arc_length_mm) - arc.begin();
        if (i >= b.points.size() || !inside(pl.center_mm)) continue;
        const Vector3d radial = (pl.center_mm - b.points[i].position_m * 1e3).normalized();
        const Vector3d halo = pl.center_mm + radial * (pl.semi_axes_mm.y() + 0.5 * c.facts.bloom_mm);
        if (!inside(halo)) continue;
        const double with = hu_at(c.ct, halo), without = hu_at(p.ct, halo);
        const double bloom_hu = c.facts.bloom_fraction * pl.hu;
        std::printf("seed %u: plaque %.0f HU; %.2f mm past its edge %.0f HU with the bloom (%.0f), %.0f without\n",
                    seed, pl.hu, 0.5 * c.facts.bloom_mm, with, bloom_hu, without);
        EXPECT_GT(with - without, std::max(30.0, 0.25 * (bloom_hu - without))) << seed;
        bloom_seen = true;
      }
    }
    if (want_laa && inside(f.laa_tip_mm)) {
      const double hu = hu_at(c.ct, f.laa_tip_mm);
      std::printf("seed %u: appendage tip %.0f HU (LA %.0f), %.2f mm from the LCx\n", seed, hu, f.la_hu, f.laa_gap_mm);
      EXPECT_NEAR(hu, f.la_hu, 60) << seed;
      laa_seen = true;
    }
  }
  EXPECT_TRUE(stent_seen);
  EXPECT_TRUE(bloom_seen);
  EXPECT_TRUE(laa_seen);
}

// the thorax painter keeps the right ventricle's blood rv_wall_mm inside the myocardium's outline
// (the heart a sphere of kPhantomHeartRadiusMm here): its outermost blood voxel lies within a
// voxel of that depth, whatever the wall
TEST(PhantomCtaFamily, TheRightVentricleReachesItsThinWall) {
  for (double wall : {2.0, 5.0}) {
    ThoraxPhantomSpec s;
    s.dims = {140, 140, 140};
    s.spacing_mm = 0.8;
    s.center_mm = Vector3d::Zero();
    s.rv_hu = 333;
    s.lv_hu = s.la_hu = s.ra_hu = s.aorta_hu = 500;
    s.coronary_lumens = false;
    s.chamber_clearance_mm = 4;
    s.rv_wall_mm = wall;
    s.rv_semi_mm = Vector3d(22, 28, 32);
    const Volume v = make_thorax_phantom(s, VesselTree{});
    double outermost = 0;
    for (int64_t k = 0; k < v.dims[2]; ++k) {
      for (int64_t j = 0; j < v.dims[1]; ++j) {
        for (int64_t i = 0; i < v.dims[0]; ++i) {
          if (v.hu(i, j, k) != 333) continue;
          outermost = std::max(outermost, v.index_to_physical_mm(Vector3d(double(i), double(j), double(k))).norm());
        }
      }
    }
    std::printf("RV wall %.1f mm: the outermost RV blood %.2f mm from the heart's centre\n", wall, outermost);
    EXPECT_LE(outermost, kPhantomHeartRadiusMm - wall + 1e-6);
    EXPECT_GE(outermost, kPhantomHeartRadiusMm - wall - 0.8);
  }
}

// a test's pins (PhantomCtaSpec::pins) set the draws they name and nothing else: the rest of the
// phantom is as drawn without them; a pin outside the family's range, or on a classic phantom, is
// refused naming it
TEST(PhantomCtaFamily, PinsSetTheirDrawsAndNothingElse) {
  const PhantomCta free = make_phantom_cta(coarse(5));
  PhantomCtaSpec s = coarse(5);
  s.pins.myocardium_hu = 150;
  s.pins.vein_hu = 300;
  s.pins.open_valve = free.facts.open_valve ? 0 : 1;
  s.pins.contrast_hu_proximal = 300;
  const PhantomCta pinned = make_phantom_cta(s);
  EXPECT_EQ(pinned.facts.myocardium_hu, 150);
  EXPECT_EQ(pinned.facts.vein_hu, 300);
  EXPECT_NE(pinned.facts.open_valve, free.facts.open_valve);
  EXPECT_EQ(pinned.facts.contrast_hu_proximal, 300);
  EXPECT_EQ(pinned.facts.aorta_hu, 300);
  EXPECT_NEAR(pinned.facts.lv_hu - pinned.facts.aorta_hu, free.facts.lv_hu - free.facts.aorta_hu, 1e-9);
  // what was not pinned is as drawn
  EXPECT_EQ(pinned.facts.rv_wall_mm, free.facts.rv_wall_mm);
  EXPECT_EQ(pinned.facts.fade_hu_per_mm, free.facts.fade_hu_per_mm);
  EXPECT_EQ(pinned.facts.stent_branch, free.facts.stent_branch);
  EXPECT_EQ(pinned.facts.side_branches, free.facts.side_branches);
  ASSERT_EQ(pinned.truth.branches.size(), free.truth.branches.size());
  // refused: out of range, on a classic phantom
  PhantomCtaSpec bad = coarse(5);
  bad.pins.rv_wall_mm = 1.0;
  try {
    make_phantom_cta(bad);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pins.rv_wall_mm"), std::string::npos) << e.what();
  }
  PhantomCtaSpec classic;
  classic.dims = {10, 10, 10};
  classic.spacing_mm = {14, 14, 14};
  classic.pins.myocardium_hu = 100;
  EXPECT_THROW(make_phantom_cta(classic), std::invalid_argument);
}

}  // namespace
}  // namespace pcisim::anatomy
