#include "anatomy/phantom/phantom_cta.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "tests/anatomy/phantom/phantom_cta_probe.h"

#ifdef PCISIM_HAVE_JSON
#include <fstream>
#include <nlohmann/json.hpp>

#include "anatomy/vessel/vessel_tree_json.h"
#include "anatomy/volume/volume_io.h"
#endif

namespace pcisim::anatomy {
namespace {

using Eigen::Vector3d;

// a small CTA: 128 mm each way at 0.8 mm (the heart and the coronaries fit)
PhantomCtaSpec small(uint32_t seed) {
  PhantomCtaSpec s;
  s.seed = seed;
  s.dims = {160, 160, 160};
  s.spacing_mm = {0.8, 0.8, 0.8};
  return s;
}

TEST(PhantomCta, SameSeedSameVolumeWhateverTheThreads) {
  PhantomCtaSpec s = small(3);
  s.threads = 1;
  const PhantomCta a = make_phantom_cta(s);
  s.threads = 3;
  const PhantomCta b = make_phantom_cta(s);
  EXPECT_EQ(validate(a.ct), "");
  EXPECT_EQ(a.ct.hu_i16, b.ct.hu_i16);
  EXPECT_EQ(a.ct.origin_mm, b.ct.origin_mm);
  ASSERT_EQ(a.truth.branches.size(), b.truth.branches.size());
  for (size_t n = 0; n < a.truth.branches.size(); ++n) {
    ASSERT_EQ(a.truth.branches[n].points.size(), b.truth.branches[n].points.size());
    for (size_t i = 0; i < a.truth.branches[n].points.size(); ++i) {
      EXPECT_EQ(a.truth.branches[n].points[i].position_m, b.truth.branches[n].points[i].position_m);
      EXPECT_EQ(a.truth.branches[n].points[i].radius_m, b.truth.branches[n].points[i].radius_m);
    }
  }
}

TEST(PhantomCta, DifferentSeedsDifferInGeometry) {
  const PhantomCta a = make_phantom_cta(small(1)), b = make_phantom_cta(small(2));
  EXPECT_NE(a.ct.hu_i16, b.ct.hu_i16);
  // the LAD's course relative to the heart centre: several mm apart somewhere
  const auto& la = branch(a, "LAD").points;
  const auto& lb = branch(b, "LAD").points;
  double most = 0;
  for (size_t i = 0; i < std::min(la.size(), lb.size()); ++i) {
    const Vector3d pa = la[i].position_m * 1e3 - a.facts.heart_center_mm;
    const Vector3d pb = lb[i].position_m * 1e3 - b.facts.heart_center_mm;
    most = std::max(most, (pa - pb).norm());
  }
  EXPECT_GT(most, 5.0);
  EXPECT_NE(a.facts.heart_rotation_deg, b.facts.heart_rotation_deg);
  EXPECT_NE(a.facts.heart_center_mm, b.facts.heart_center_mm);
  // across seeds the drawn quantities cover their ranges
  bool lad = false, rca = false, dropped = false, kept = false;
  for (uint32_t seed = 1; seed <= 12; ++seed) {
    PhantomCtaSpec s = small(seed);
    s.dims = {10, 10, 10};  // geometry and facts only: coarse voxels, the same 126 mm field
    s.spacing_mm = {14, 14, 14};
    const PhantomCta c = make_phantom_cta(s);
    const auto& f = c.facts;
    lad = lad || f.stenosis_branch == "LAD";
    rca = rca || f.stenosis_branch == "RCA";
    dropped = dropped || !f.dropped_branches.empty();
    kept = kept || f.dropped_branches.empty();
    EXPECT_GE(f.contrast_hu_proximal, 300);
    EXPECT_LE(f.contrast_hu_proximal, 550);
    EXPECT_GE(f.rv_hu, 100);
    EXPECT_LE(f.rv_hu, 400);
    EXPECT_GE(f.heart_scale, 0.9);
    EXPECT_LE(f.heart_scale, 1.1);
    EXPECT_LE(f.heart_rotation_deg.cwiseAbs().maxCoeff(), 15.0);
    EXPECT_GE(f.plaques.size(), 1u);
    EXPECT_LE(f.plaques.size(), 3u);
    EXPECT_GE(f.stenosis_fraction, 0.5);
    EXPECT_LE(f.stenosis_fraction, 0.8);
    EXPECT_EQ(c.truth.find("D2") < 0, std::count(f.dropped_branches.begin(), f.dropped_branches.end(), "D2") == 1);
  }
  EXPECT_TRUE(lad && rca && dropped && kept);
}

TEST(PhantomCta, ContrastFadesAlongTheLad) {
  for (uint32_t seed : {1u, 5u}) {
    const PhantomCta c = make_phantom_cta(small(seed));
    const auto& lad = branch(c, "LAD");
    const auto s = arcs_mm(lad);
    // the LM's path from its ostium, for the expected proximal value
    const auto& lm = branch(c, "LM");
    const Vector3d ostium = landmark_mm(c, "LM ostium");
    size_t o = 0;
    for (size_t i = 0; i < lm.points.size(); ++i) {
      if ((lm.points[i].position_m * 1e3 - ostium).norm() < (lm.points[o].position_m * 1e3 - ostium).norm()) o = i;
    }
    const auto lm_s = arcs_mm(lm);
    const double lm_path = lm_s.back() - lm_s[o];
    double prox = 0, expected = 0, dist = 0;
    int np = 0, nd = 0;
    for (size_t i = 0; i < lad.points.size(); ++i) {
      const Vector3d p = lad.points[i].position_m * 1e3;
      if (s[i] > 5 && s[i] < 25 && lad.points[i].radius_m > 1.0e-3) {
        prox += hu_at(c.ct, p);
        expected +=
            std::max(c.facts.lumen_floor_hu, c.facts.contrast_hu_proximal - c.facts.fade_hu_per_mm * (lm_path + s[i]));
        ++np;
      } else if (s[i] > 0.75 * s.back()) {
        dist += hu_at(c.ct, p);
        ++nd;
      }
    }
    ASSERT_GT(np, 10);
    ASSERT_GT(nd, 10);
    prox /= np;
    expected /= np;
    dist /= nd;
    EXPECT_GE(prox, 250) << "seed " << seed;
    EXPECT_LE(prox, 550) << "seed " << seed;
    EXPECT_NEAR(prox, expected, 0.12 * expected) << "seed " << seed;
    EXPECT_LT(dist, prox - 20) << "seed " << seed;
    std::printf("seed %u: proximal LAD %.0f HU (lumen %.0f), distal %.0f\n", seed, prox, expected, dist);
  }
}

TEST(PhantomCta, AorticSeedAndOutflowTractAreBright) {
  PhantomCtaSpec s = small(2);
  const PhantomCta c = make_phantom_cta(s);
  EXPECT_GT(hu_at(c.ct, c.aortic_seed_mm), 250);
  EXPECT_NEAR(hu_at(c.ct, c.aortic_seed_mm), c.facts.aorta_hu, 4 * s.noise_sigma_hu);
  // the outflow tract joins the aortic root to the LV cavity: bright all the way (no noise)
  s.noise_sigma_hu = 0;
  const PhantomCta quiet = make_phantom_cta(s);
  const Vector3d root = landmark_mm(quiet, "aortic root"), lv = quiet.facts.lv_center_mm;
  for (int n = 0; n <= 50; ++n) {
    const Vector3d p = root + (lv - root) * (n / 50.0);
    EXPECT_GT(hu_at(quiet.ct, p), 250) << n;
  }
}

TEST(PhantomCta, NoiseHasTheSpecifiedSigma) {
  for (double sigma : {25.0, 40.0}) {
    PhantomCtaSpec s = small(4);
    s.noise_sigma_hu = sigma;
    const PhantomCta c = make_phantom_cta(s);
    // a 9x9x9 cube at the LV cavity's centre (its semi-axes are >= 15 mm): uniform blood
    const Vector3d ijk = c.ct.physical_to_index(c.facts.lv_center_mm);
    double sum = 0, sum2 = 0;
    int n = 0;
    for (int dz = -4; dz <= 4; ++dz) {
      for (int dy = -4; dy <= 4; ++dy) {
        for (int dx = -4; dx <= 4; ++dx) {
          const double h = c.ct.hu(std::lround(ijk.x()) + dx, std::lround(ijk.y()) + dy, std::lround(ijk.z()) + dz);
          sum += h;
          sum2 += h * h;
          ++n;
        }
      }
    }
    const double mean = sum / n, sd = std::sqrt(std::max(0.0, sum2 / n - mean * mean));
    EXPECT_NEAR(mean, c.facts.lv_hu, 5.0);
    EXPECT_NEAR(sd, sigma, 0.15 * sigma);
  }
}

TEST(PhantomCta, StenosisInTheTruthRadii) {
  for (double fraction : {0.95, -1.0}) {
    PhantomCtaSpec s = small(6);
    s.scanner_frame = false;
    s.stenosis_fraction = fraction;
    const PhantomCta c = make_phantom_cta(s);
    const auto& f = c.facts;
    if (fraction > 0) {
      EXPECT_EQ(f.stenosis_fraction, fraction);
    }
    const auto& b = branch(c, f.stenosis_branch);
    const auto arc = arcs_mm(b);
    size_t centre = 0;
    for (size_t i = 0; i < b.points.size(); ++i) {
      if (std::abs(arc[i] - f.stenosis_arc_length_mm) < std::abs(arc[centre] - f.stenosis_arc_length_mm)) centre = i;
    }
    EXPECT_NEAR(arc[centre], f.stenosis_arc_length_mm, 1e-9);
    EXPECT_NEAR((b.points[centre].position_m * 1e3 - f.stenosis_center_mm).norm(), 0.0, 1e-9);
    EXPECT_NEAR(b.points[centre].radius_m * 1e3, f.stenosis_reference_radius_mm * (1 - f.stenosis_fraction), 1e-9);
    // the narrowest point of the branch is the stenosis; beyond its length the radius is whole
    double narrowest = 1e9;
    for (const auto& p : b.points) narrowest = std::min(narrowest, p.radius_m * 1e3);
    EXPECT_NEAR(narrowest, b.points[centre].radius_m * 1e3, 1e-9);
    size_t beyond = centre;
    while (beyond > 0 && arc[centre] - arc[beyond] <= 0.5 * f.stenosis_length_mm) --beyond;
    EXPECT_GT(b.points[beyond].radius_m * 1e3, 0.95 * f.stenosis_reference_radius_mm);
    EXPECT_GE(f.stenosis_length_mm, 4.0);
    EXPECT_LE(f.stenosis_length_mm, 8.0);
  }
}

TEST(PhantomCta, CalcifiedPlaquesAgainstTheLumen) {
  int seen = 0;
  for (uint32_t seed : {1u, 3u, 4u}) {
    // at 0.5 mm (clinical spacing is 0.3..0.8): at 0.8 mm a 700 HU plaque 1.6 mm thick,
    // blurred and mixed with fat, peaks below 600
    PhantomCtaSpec s = small(seed);
    s.dims = {256, 256, 256};
    s.spacing_mm = {0.5, 0.5, 0.5};
    const PhantomCta c = make_phantom_cta(s);
    for (const auto& pl : c.facts.plaques) {
      ++seen;
      EXPECT_GE(pl.hu, 700);
      EXPECT_LE(pl.hu, 1200);
      // the brightest voxel within 1.5 mm of the plaque's centre
      const Vector3d ijk = c.ct.physical_to_index(pl.center_mm);
      double brightest = -2000;
      for (int dz = -2; dz <= 2; ++dz) {
        for (int dy = -2; dy <= 2; ++dy) {
          for (int dx = -2; dx <= 2; ++dx) {
            brightest = std::max<double>(
                brightest, c.ct.hu(std::lround(ijk.x()) + dx, std::lround(ijk.y()) + dy, std::lround(ijk.z()) + dz));
          }
        }
      }
      EXPECT_GT(brightest, 600) << "seed " << seed << " " << pl.branch << " at " << pl.arc_length_mm << " mm";
      // in the wall: its centre outside the lumen by its radial semi-axis
      const auto& b = branch(c, pl.branch);
      double clearance = 1e9;
      for (const auto& p : b.points) {
        clearance = std::min(clearance, (p.position_m * 1e3 - pl.center_mm).norm() - p.radius_m * 1e3);
      }
      EXPECT_GT(clearance, 0.9 * pl.semi_axes_mm.y()) << "seed " << seed;
    }
  }
  EXPECT_GE(seen, 3);
}

TEST(PhantomCta, VeinDarkerThanTheArteryBesideIt) {
  for (uint32_t seed : {1u, 5u}) {
    const PhantomCta c = make_phantom_cta(small(seed));
    const auto& f = c.facts;
    ASSERT_GT(f.vein_points_mm.size(), 40u);
    EXPECT_GE(f.vein_length_mm, 30.0 - 12.0);
    EXPECT_GE(f.vein_radius_mm, 1.0);
    EXPECT_LE(f.vein_radius_mm, 1.5);
    double vein = 0;
    for (const auto& p : f.vein_points_mm) vein += hu_at(c.ct, p);
    vein /= f.vein_points_mm.size();
    const auto& b = branch(c, f.vein_beside);
    const auto arc = arcs_mm(b);
    double artery = 0;
    int n = 0;
    double touch = 1e9;
    for (size_t i = 0; i < b.points.size(); ++i) {
      if (arc[i] < f.vein_start_mm || arc[i] > f.vein_start_mm + f.vein_length_mm) continue;
      artery += hu_at(c.ct, b.points[i].position_m * 1e3);
      ++n;
      for (const auto& q : f.vein_points_mm) {
        touch = std::min(touch, (q - b.points[i].position_m * 1e3).norm() - f.vein_radius_mm);
      }
    }
    artery /= n;
    EXPECT_LT(vein, artery - 30) << "seed " << seed;
    EXPECT_GT(vein, 50) << "seed " << seed;
    // the surfaces meet: the vein's surface is within the artery's (healthy) radius of its axis
    EXPECT_LT(touch, 2.5);
    std::printf("seed %u: vein beside %s %.0f HU (drawn %.0f), artery %.0f\n", seed, f.vein_beside.c_str(), vein,
                f.vein_hu, artery);
  }
}

TEST(PhantomCta, WithoutCoronariesNothingBrightAlongTheirPaths) {
  PhantomCtaSpec s = small(2);
  s.noise_sigma_hu = 0;
  s.with_coronaries = false;
  const PhantomCta without = make_phantom_cta(s);
  s.with_coronaries = true;
  const PhantomCta with = make_phantom_cta(s);
  const auto& aorta = branch(with, "aorta").points;
  const double aorta_r = aorta.front().radius_m * 1e3;
  int checked = 0, bright_without = 0, bright_with = 0;
  for (const auto& b : with.truth.branches) {
    if (b.name == "aorta") continue;
    for (const auto& p : b.points) {
      const Vector3d q = p.position_m * 1e3;
      // leave out the aortic root and its outflow tract
      double to_aorta = 1e9;
      for (const auto& a : aorta) to_aorta = std::min(to_aorta, (a.position_m * 1e3 - q).norm());
      if (to_aorta < aorta_r + 8 || p.radius_m < 1.0e-3) continue;
      ++checked;
      // 150 HU: above fat and enhanced myocardium; a 1 mm lumen at 0.8 mm voxels, blurred,
      // reads ~180 at its floor of 250
      bright_without += hu_at(without.ct, q) > 150;
      bright_with += hu_at(with.ct, q) > 150;
    }
  }
  ASSERT_GT(checked, 200);
  EXPECT_EQ(bright_without, 0);
  EXPECT_GT(bright_with, 0.9 * checked);
  // the rest is the same volume: the aortic seed and the LV
  EXPECT_EQ(hu_at(without.ct, without.aortic_seed_mm), hu_at(with.ct, with.aortic_seed_mm));
  EXPECT_EQ(hu_at(without.ct, without.facts.lv_center_mm), hu_at(with.ct, with.facts.lv_center_mm));
}

TEST(PhantomCta, DirectionReordersTheVoxelsExactly) {
  PhantomCtaSpec s = small(7);
  s.dims = {120, 140, 130};
  s.spacing_mm = {0.9, 1.0, 1.1};
  const PhantomCta a = make_phantom_cta(s);
  Eigen::Matrix3d flip = Eigen::Vector3d(1, 1, -1).asDiagonal();
  Eigen::Matrix3d swap;
  swap << 0, -1, 0, 1, 0, 0, 0, 0, 1;  // index axis 0 runs along physical y, axis 1 along -x
  for (const Eigen::Matrix3d& d : {flip, swap}) {
    PhantomCtaSpec t = s;
    t.direction = d;
    // the spacing follows the index axes: index axis a keeps the physical axis's spacing
    for (int a = 0; a < 3; ++a) {
      for (int r = 0; r < 3; ++r) {
        if (d(r, a) != 0) t.spacing_mm[a] = s.spacing_mm[r], t.dims[a] = s.dims[r];
      }
    }
    const PhantomCta b = make_phantom_cta(t);
    EXPECT_EQ(validate(b.ct), "");
    EXPECT_EQ(b.ct.direction, d);
    // every voxel of a holds the same HU as the voxel of b at the same physical point (noise
    // included: it is drawn before the voxels are re-ordered)
    int64_t mismatches = 0;
    for (int64_t k = 0; k < a.ct.dims[2]; ++k) {
      for (int64_t j = 0; j < a.ct.dims[1]; ++j) {
        for (int64_t i = 0; i < a.ct.dims[0]; ++i) {
          const Vector3d q = b.ct.physical_to_index(a.ct.index_to_physical_mm(Vector3d(i, j, k)));
          const Vector3d r = q.array().round();
          ASSERT_LT((q - r).norm(), 1e-6);
          mismatches += a.ct.hu(i, j, k) != b.ct.hu(std::llround(r.x()), std::llround(r.y()), std::llround(r.z()));
        }
      }
    }
    EXPECT_EQ(mismatches, 0);
    EXPECT_EQ(a.truth.branches.size(), b.truth.branches.size());
    EXPECT_EQ(a.truth.branches[2].points[10].position_m, b.truth.branches[2].points[10].position_m);
  }
  Eigen::Matrix3d bad = Eigen::Matrix3d::Identity();
  bad(0, 1) = 1;
  PhantomCtaSpec t = s;
  t.direction = bad;
  EXPECT_THROW(make_phantom_cta(t), std::invalid_argument);
}

TEST(PhantomCta, TruthAndLandmarksInsideTheVolume) {
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    PhantomCtaSpec s = small(seed);
    s.noise_sigma_hu = 0;
    s.blur_sigma_mm = 0;
    s.scanner_frame = seed % 2 == 0;
    const PhantomCta c = make_phantom_cta(s);
    for (const auto& b : c.truth.branches) {
      for (const auto& p : b.points) EXPECT_TRUE(in_grid(c.ct, c.ct.physical_to_index(p.position_m * 1e3)));
    }
    for (const auto& l : c.landmarks) {
      EXPECT_TRUE(in_grid(c.ct, c.ct.physical_to_index(l.position_m * 1e3))) << l.name << " seed " << seed;
    }
    // a 128 mm field holds every coronary branch whole; only the aorta may leave it
    for (const auto& name : c.facts.clipped_branches) EXPECT_EQ(name, "aorta") << "seed " << seed;
    for (const char* name : {"aorta", "LM", "LAD", "LCx", "D1", "OM1", "RCA"}) {
      EXPECT_GE(c.truth.find(name), 0) << name;
    }
    if (s.scanner_frame) {
      const Vector3d h = c.facts.heart_center_mm;
      EXPECT_LE(std::abs(h.x()), 30);
      EXPECT_NEAR(h.y(), -120, 30);
      EXPECT_NEAR(h.z(), -150, 40);
    } else {
      EXPECT_EQ(c.facts.heart_center_mm, Vector3d::Zero());
    }
  }
}

TEST(PhantomCta, ScannerFrameMovesEverythingRigidly) {
  PhantomCtaSpec s = small(8);
  s.noise_sigma_hu = 0;
  const PhantomCta moved = make_phantom_cta(s);
  s.scanner_frame = false;
  const PhantomCta centred = make_phantom_cta(s);
  EXPECT_EQ(moved.ct.hu_i16, centred.ct.hu_i16);
  const Vector3d offset = moved.facts.heart_center_mm;
  EXPECT_GT(offset.norm(), 50);
  EXPECT_LT((moved.ct.origin_mm - centred.ct.origin_mm - offset).norm(), 1e-9);
  const auto& a = branch(moved, "RCA").points;
  const auto& b = branch(centred, "RCA").points;
  ASSERT_EQ(a.size(), b.size());
  EXPECT_LT((a.back().position_m * 1e3 - b.back().position_m * 1e3 - offset).norm(), 1e-9);
}

TEST(PhantomCta, RefusesBadSpecs) {
  PhantomCtaSpec s = small(1);
  s.dims[1] = 0;
  EXPECT_THROW(make_phantom_cta(s), std::invalid_argument);
  s = small(1);
  s.spacing_mm.z() = -0.5;
  EXPECT_THROW(make_phantom_cta(s), std::invalid_argument);
  s = small(1);
  s.stenosis_fraction = 1.0;
  EXPECT_THROW(make_phantom_cta(s), std::invalid_argument);
  s = small(1);
  s.noise_sigma_hu = -1;
  EXPECT_THROW(make_phantom_cta(s), std::invalid_argument);
}

#ifdef PCISIM_HAVE_JSON
TEST(PhantomCta, WritesCtTruthAndFacts) {
  PhantomCtaSpec s = small(9);
  s.dims = {96, 100, 104};
  s.spacing_mm = {1.4, 1.3, 1.35};
  s.direction = Eigen::Vector3d(1, 1, -1).asDiagonal();
  const PhantomCta c = make_phantom_cta(s);
  const std::string dir = ::testing::TempDir() + "phantom_cta_write";
  std::filesystem::remove_all(dir);
  write_phantom_cta(c, dir);
  const Volume v = read_volume(dir + "/ct.nrrd", true);
  EXPECT_EQ(v.hu_i16, c.ct.hu_i16);
  EXPECT_LT((v.origin_mm - c.ct.origin_mm).norm(), 1e-9);
  EXPECT_LT((v.direction - c.ct.direction).norm(), 1e-12);
  const VesselTree t = read_vessel_tree_json(dir + "/truth.json");
  ASSERT_EQ(t.branches.size(), c.truth.branches.size());
  EXPECT_EQ(t.branches[3].points[5].position_m, c.truth.branches[3].points[5].position_m);
  std::ifstream in(dir + "/phantom.json");
  const nlohmann::json doc = nlohmann::json::parse(in);
  EXPECT_EQ(doc["format"], "pcisim-phantom-cta");
  EXPECT_EQ(doc["spec"]["seed"], 9);
  EXPECT_EQ(doc["facts"]["stenosis"]["branch"], c.facts.stenosis_branch);
  EXPECT_EQ(doc["facts"]["plaques"].size(), c.facts.plaques.size());
  EXPECT_EQ(doc["landmarks"].size(), c.landmarks.size());
  EXPECT_EQ(doc["aortic_seed_mm"][2].get<double>(), c.aortic_seed_mm.z());
  std::filesystem::remove_all(dir);
}
#endif

// the clinical size, timed: run with --gtest_also_run_disabled_tests
TEST(PhantomCta, DISABLED_TimeAClinicalVolume) {
  const auto t0 = std::chrono::steady_clock::now();
  const PhantomCta c = make_phantom_cta(PhantomCtaSpec{});
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("make_phantom_cta %lldx%lldx%lld: %.2f s\n", static_cast<long long>(c.ct.dims[0]),
              static_cast<long long>(c.ct.dims[1]), static_cast<long long>(c.ct.dims[2]), s);
  EXPECT_LT(s, 30.0);
}

}  // namespace
}  // namespace pcisim::anatomy
