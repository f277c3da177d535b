#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/xray/projectors/projector_test_util.h"
#include "xray/projectors/siddon_projector.h"
#include "xray/projectors/ray_packet.h"
#include "xray/projectors/trilinear_projector.h"

namespace pcisim::xray {
namespace {

using Eigen::Vector3d;
using testing::random_geometry;
using testing::random_volume;
using testing::uniform;

struct Errors {
  double rmse_rel = 0, max_rel = 0;  // relative to the largest reference value
};

Errors compare(const Image& got, const Image& ref) {
  double peak = 0, sq = 0, worst = 0;
  for (size_t n = 0; n < ref.pixels.size(); ++n) peak = std::max(peak, double(std::abs(ref.pixels[n])));
  for (size_t n = 0; n < ref.pixels.size(); ++n) {
    const double e = got.pixels[n] - ref.pixels[n];
    sq += e * e;
    worst = std::max(worst, std::abs(e));
  }
  return {std::sqrt(sq / ref.pixels.size()) / peak, worst / peak};
}

// the nearest-voxel mu along a segment by brute-force fine sampling: an independent check
double brute_force_nearest(const AttenuationVolume& a, const Vector3d& p0, const Vector3d& p1, int samples) {
  double sum = 0;
  for (int s = 0; s < samples; ++s) {
    const Vector3d p = p0 + (s + 0.5) / samples * (p1 - p0);
    const Vector3d idx = a.index_from_physical() * p + a.index_offset();
    const int i = int(std::lround(idx.x())), j = int(std::lround(idx.y())), k = int(std::lround(idx.z()));
    if (i < 0 || j < 0 || k < 0 || i >= a.dims()[0] || j >= a.dims()[1] || k >= a.dims()[2]) continue;
    sum += a.mu(i, j, k);
  }
  return sum * (p1 - p0).norm() / samples;
}

TEST(SiddonProjector, MatchesBruteForceNearestVoxelOnRandomVolumes) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 4; ++trial) {
    const anatomy::Volume v = random_volume(rng, /*smooth=*/false);
    const AttenuationVolume a(v);
    const DetectorGeometry g = random_geometry(rng, v, 6, 5);
    for (int r = 0; r < g.height; ++r) {
      for (int c = 0; c < g.width; ++c) {
        const Vector3d p = g.pixel_center_mm(c, r);
        const double exact = exact_line_integral(a, g.source_mm, p);
        const double brute = brute_force_nearest(a, g.source_mm, p, 400000);
        // fine sampling misplaces each voxel boundary by at most half a sample
        EXPECT_NEAR(exact, brute, 2e-3 * std::max(1.0, brute)) << "trial " << trial << " pixel " << c << "," << r;
      }
    }
  }
}

// the projector's fast path (brick skipping, strided traversal) gives exact_line_integral's sums
TEST(SiddonProjector, FastPathEqualsTheReferenceTraversal) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 3; ++trial) {
    const anatomy::Volume v = random_volume(rng, /*smooth=*/true);  // blobs in air: empty bricks
    AttenuationParams params;
    params.brick_voxels = 3;
    const AttenuationVolume a(v, params);
    const DetectorGeometry g = random_geometry(rng, v, 24, 18);
    Image img;
    img.resize(g.width, g.height);
    SiddonProjector(a, 2).project(g, &img);
    for (int r = 0; r < g.height; ++r) {
      for (int c = 0; c < g.width; ++c) {
        const double want = exact_line_integral(a, g.source_mm, g.pixel_center_mm(c, r));
        EXPECT_NEAR(img.at(c, r), want, 1e-6 * std::max(want, 1e-3)) << trial << ": " << c << "," << r;
      }
    }
  }
}

// the exact projector plans with bricks coarser than the volume's; where the volume's bricks were
// rebuilt after mu was written in place (the beating background does), the next projection plans
// with the new ones: a cube put in the air between two others is seen, through the fast path, as
// exact_line_integral sees it
TEST(SiddonProjector, PlansWithTheBricksAsTheyAreWhenItProjects) {
  anatomy::Volume v = anatomy::Volume::make({96, 80, 72}, Vector3d(0.5, 0.5, 0.5), Vector3d(-24, -20, -18),
                                            anatomy::VoxelType::kFloat32);
  std::fill(v.hu_f32.begin(), v.hu_f32.end(), -1000.0f);
  auto cube = [&](anatomy::Volume& vol, int i0, int j0, int k0, int size, float hu) {
    for (int k = k0; k < k0 + size; ++k)
      for (int j = j0; j < j0 + size; ++j)
        for (int i = i0; i < i0 + size; ++i) vol.hu_f32[vol.linear_index(i, j, k)] = hu;
  };
  cube(v, 4, 4, 4, 10, 800.0f);
  cube(v, 80, 64, 56, 10, 400.0f);
  AttenuationParams params;
  params.brick_voxels = 4;  // the projector's bricks: 16 voxels, the middle cube's stretch empty
  AttenuationVolume a(v, params);
  // looking along y through the middle of the volume
  DetectorGeometry g;
  g.source_mm = Vector3d(0, 400, 0);
  g.center_mm = Vector3d(0, -300, 0);
  g.pixel_mm = 1.0;
  g.width = 48;
  g.height = 40;
  SiddonProjector projector(a, 2);
  Image before, after;
  before.resize(g.width, g.height);
  after.resize(g.width, g.height);
  projector.project(g, &before);
  // a cube of mu 0.05 /mm in the middle, written in place, the bricks rebuilt
  const int p0 = a.padded_dims()[0], p01 = p0 * a.padded_dims()[1];
  for (int k = 30; k < 40; ++k)
    for (int j = 34; j < 44; ++j)
      for (int i = 42; i < 52; ++i) a.mutable_padded_mu()[(i + 1) + p0 * (j + 1) + int64_t(p01) * (k + 1)] = 0.05f;
  a.rebuild_bricks();
  projector.project(g, &after);
  int changed = 0;
  for (int r = 0; r < g.height; ++r) {
    for (int c = 0; c < g.width; ++c) {
      const double want = exact_line_integral(a, g.source_mm, g.pixel_center_mm(c, r));
      EXPECT_NEAR(after.at(c, r), want, 1e-6 * std::max(want, 1e-3)) << c << "," << r;
      changed += after.at(c, r) > before.at(c, r) + 0.1f;
    }
  }
  // the middle cube's shadow: 5 mm across, magnified 700 / 400: about 9 x 9 pixels
  EXPECT_GT(changed, 20);
}

// a water box (HU 0 -> mu_water) with faces on voxel boundaries: the exact integral of any ray
// is mu_water times the length of its chord through the box, in closed form by slab clipping
// water (0 HU) on voxel boundaries in air, anisotropic voxels; chord_mm: the segment's length
// inside it, in closed form
struct WaterBox {
  anatomy::Volume v;
  Vector3d lo_mm, hi_mm;
  WaterBox()
      : v(anatomy::Volume::make({40, 36, 30}, Vector3d(0.5, 0.75, 1.0), Vector3d(-10, -13, -15),
                                anatomy::VoxelType::kInt16)) {
    std::fill(v.hu_i16.begin(), v.hu_i16.end(), int16_t(-1000));
    const int lo[3] = {8, 6, 5}, hi[3] = {31, 27, 24};  // inclusive voxel ranges
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) v.hu_i16[v.linear_index(i, j, k)] = 0;
    lo_mm = v.index_to_physical_mm(Vector3d(lo[0] - 0.5, lo[1] - 0.5, lo[2] - 0.5));
    hi_mm = v.index_to_physical_mm(Vector3d(hi[0] + 0.5, hi[1] + 0.5, hi[2] + 0.5));
  }
  double chord_mm(const Vector3d& p0, const Vector3d& p1) const {
    double t0 = 0, t1 = 1;
    for (int ax = 0; ax < 3; ++ax) {
      const double d = p1[ax] - p0[ax];
      if (std::abs(d) < 1e-15) {
        if (p0[ax] < lo_mm[ax] || p0[ax] > hi_mm[ax]) return 0.0;
        continue;
      }
      double ta = (lo_mm[ax] - p0[ax]) / d, tb = (hi_mm[ax] - p0[ax]) / d;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    return std::max(0.0, t1 - t0) * (p1 - p0).norm();
  }
};

TEST(Projectors, WaterBoxMatchesClosedForm) {
  const WaterBox box;
  const anatomy::Volume& v = box.v;
  const AttenuationVolume a(v);
  auto chord = [&](const Vector3d& p0, const Vector3d& p1) { return box.chord_mm(p0, p1); };
  std::mt19937 rng(5);
  DetectorGeometry g = random_geometry(rng, v, 24, 20);
  g.pixel_mm *= 0.5;  // keep most rays on the box
  Image exact, tri;
  exact.resize(g.width, g.height);
  tri.resize(g.width, g.height);
  SiddonProjector(a, 2).project(g, &exact);
  TrilinearProjector(a, {.step_voxels = 0.25, .skip_empty = true, .threads = 2}).project(g, &tri);
  double peak = 0, tri_err = 0;
  int hits = 0;
  for (int r = 0; r < g.height; ++r) {
    for (int c = 0; c < g.width; ++c) {
      const double want = 0.02 * chord(g.source_mm, g.pixel_center_mm(c, r));
      peak = std::max(peak, want);
      hits += want > 0;
      EXPECT_NEAR(exact.at(c, r), want, 1e-4 * std::max(want, 1e-3)) << c << "," << r;
      tri_err = std::max(tri_err, std::abs(tri.at(c, r) - want));
    }
  }
  EXPECT_GT(hits, g.width * g.height / 3);
  // trilinear blurs the faces over one voxel; at 0.25 voxel steps the worst ray stays within 3 %
  // of the largest integral (corner-grazing rays), in practice ~1 %
  EXPECT_LT(tri_err, 0.03 * peak);
  RecordProperty("trilinear_box_max_rel", std::to_string(tri_err / peak));
}

// a water cylinder along z: rays parallel to the axis see mu_water times the height (exact),
// rays across it the chord 2 sqrt(R^2 - d^2) up to the voxelised outline (about a voxel per side)
TEST(Projectors, WaterCylinderMatchesClosedForm) {
  const int n = 48, nz = 20;
  const double s = 0.5, radius_mm = 9.0;
  anatomy::Volume v = anatomy::Volume::make(
      {n, n, nz}, Vector3d(s, s, s), Vector3d(-(n - 1) * s / 2, -(n - 1) * s / 2, 0), anatomy::VoxelType::kInt16);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vector3d p = v.index_to_physical_mm(Vector3d(i, j, k));
        v.hu_i16[v.linear_index(i, j, k)] = std::hypot(p.x(), p.y()) <= radius_mm ? 0 : -1000;
      }
  const AttenuationVolume a(v);
  const double height_mm = nz * s, mu = 0.02;
  TrilinearProjector tri(a, {.step_voxels = 0.25, .skip_empty = true, .threads = 1});
  // along the axis, from far below to far above, through interior points
  for (double x : {0.0, 3.1, -5.2}) {
    for (double y : {0.0, 2.2}) {
      const Vector3d p0(x, y, -100), p1(x, y, 100);
      EXPECT_NEAR(exact_line_integral(a, p0, p1), mu * height_mm, 1e-4 * mu * height_mm);
      DetectorGeometry g;  // one pixel on the same ray
      g.source_mm = p0;
      g.center_mm = p1;
      g.u = Vector3d::UnitX();
      g.v = Vector3d::UnitY();
      g.width = g.height = 1;
      Image img;
      img.resize(1, 1);
      tri.project(g, &img);
      // trilinear ramps over half a voxel at each end face: the areas match, so the sum does too
      EXPECT_NEAR(img.at(0, 0), mu * height_mm, 0.01 * mu * height_mm);
    }
  }
  // across the axis at offsets d, in the middle slice
  for (double d : {0.0, 2.0, 4.5, 7.0}) {
    const Vector3d p0(-100, d, 5.0 + 0.1), p1(100, d, 5.0 + 0.1);
    const double want = mu * 2 * std::sqrt(radius_mm * radius_mm - d * d);
    EXPECT_NEAR(exact_line_integral(a, p0, p1), want, mu * 2 * s) << d;
  }
}

TEST(TrilinearProjector, ConvergesToExactOnSmoothRandomVolumes) {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 3; ++trial) {
    const anatomy::Volume v = random_volume(rng, /*smooth=*/true);
    const AttenuationVolume a(v);
    const DetectorGeometry g = random_geometry(rng, v, 20, 16);
    Image exact, fine, coarse;
    exact.resize(g.width, g.height);
    fine.resize(g.width, g.height);
    coarse.resize(g.width, g.height);
    SiddonProjector(a, 2).project(g, &exact);
    TrilinearProjector tp(a, {.step_voxels = 0.25, .skip_empty = true, .threads = 2});
    tp.project(g, &fine);
    tp.set_options({.step_voxels = 2.0, .skip_empty = true});
    tp.project(g, &coarse);
    const Errors ef = compare(fine, exact), ec = compare(coarse, exact);
    // the smooth blobs span ~3-5 voxels: nearest vs trilinear differ by ~1 % rms, < 6 % worst ray
    EXPECT_LT(ef.rmse_rel, 0.01) << trial;
    EXPECT_LT(ef.max_rel, 0.06) << trial;
    EXPECT_LE(ef.rmse_rel, ec.rmse_rel + 1e-6) << trial;
  }
}

TEST(TrilinearProjector, SkippingEmptySpaceChangesNothingAndThreadsChangeNothing) {
  std::mt19937 rng(8);
  const anatomy::Volume v = random_volume(rng, /*smooth=*/true);  // blobs in air: many empty bricks
  AttenuationParams params;
  params.brick_voxels = 4;
  const AttenuationVolume a(v, params);
  int empty = 0;
  for (float m : a.brick_max()) empty += m == 0.f;
  ASSERT_GT(empty, 0) << "the test needs empty bricks";
  const DetectorGeometry g = random_geometry(rng, v, 32, 24);
  Image skip, full, one;
  skip.resize(g.width, g.height);
  full.resize(g.width, g.height);
  one.resize(g.width, g.height);
  TrilinearProjector(a, {.step_voxels = 0.5, .skip_empty = true, .threads = 3}).project(g, &skip);
  TrilinearProjector(a, {.step_voxels = 0.5, .skip_empty = false, .threads = 3}).project(g, &full);
  TrilinearProjector(a, {.step_voxels = 0.5, .skip_empty = true, .threads = 1}).project(g, &one);
  const Errors e = compare(skip, full);
  EXPECT_LT(e.max_rel, 1e-5);
  EXPECT_EQ(skip.pixels, one.pixels);
}

TEST(TrilinearProjector, EightRaysAtOnceTakeTheSameSamplesAsOneAtATime) {
  if (!ray::packet_supported()) GTEST_SKIP() << "this CPU has no AVX2: the packets are not used";
  std::mt19937 rng(31);
  for (int trial = 0; trial < 4; ++trial) {
    const anatomy::Volume v = random_volume(rng, /*smooth=*/true);
    AttenuationParams params;
    params.brick_voxels = 2 + trial;  // many empty bricks, runs that start and stop
    const AttenuationVolume a(v, params);
    // 37 columns: four packets of eight and five rays one at a time in every row; trials 2 and 3
    // widen the pixels so the detector overhangs the volume and packets hold rays that miss it
    DetectorGeometry g = random_geometry(rng, v, 37, 11);
    if (trial >= 2) g.pixel_mm *= 2.5;
    for (const double step : {0.3, 1.0}) {
      for (const bool skip : {true, false}) {
        Image packed, single;
        packed.resize(g.width, g.height);
        single.resize(g.width, g.height);
        TrilinearProjector(a, {.step_voxels = step, .skip_empty = skip, .threads = 2, .packets = true})
            .project(g, &packed);
        TrilinearProjector(a, {.step_voxels = step, .skip_empty = skip, .threads = 2, .packets = false})
            .project(g, &single);
        // the same samples; positions stepped instead of recomputed move the sums in the last bits
        const Errors e = compare(packed, single);
        EXPECT_LT(e.max_rel, 2e-5) << trial << " step " << step << " skip " << skip;
        double top = 0;
        for (const float p : single.pixels) top = std::max<double>(top, p);
        ASSERT_GT(top, 0) << "the rays must cross the volume";
      }
    }
  }
}

// Joseph's method (TrilinearOptions::slices): one bilinear read per voxel plane of the ray's major
// axis, against the closed-form chord of a water box; trilinear at 1 voxel beside it, the marcher
// the scenes ran before
TEST(SliceProjector, WaterBoxMatchesClosedFormAsTrilinearDoes) {
  const WaterBox box;
  const anatomy::Volume& v = box.v;
  const AttenuationVolume a(v);
  std::mt19937 rng(5);
  for (int view = 0; view < 3; ++view) {
    DetectorGeometry g = random_geometry(rng, v, 24, 20);
    g.pixel_mm *= 0.5;
    Image slices, tri;
    slices.resize(g.width, g.height);
    tri.resize(g.width, g.height);
    TrilinearProjector(a, {.step_voxels = 1.0, .skip_empty = true, .threads = 2, .slices = true}).project(g, &slices);
    TrilinearProjector(a, {.step_voxels = 1.0, .skip_empty = true, .threads = 2}).project(g, &tri);
    double peak = 0, slice_sq = 0, tri_sq = 0, slice_worst = 0, tri_worst = 0;
    int hits = 0;
    for (int r = 0; r < g.height; ++r) {
      for (int c = 0; c < g.width; ++c) {
        const double want = 0.02 * box.chord_mm(g.source_mm, g.pixel_center_mm(c, r));
        peak = std::max(peak, want);
        hits += want > 0;
        slice_sq += std::pow(slices.at(c, r) - want, 2);
        tri_sq += std::pow(tri.at(c, r) - want, 2);
        slice_worst = std::max(slice_worst, std::abs(slices.at(c, r) - want));
        tri_worst = std::max(tri_worst, std::abs(tri.at(c, r) - want));
      }
    }
    ASSERT_GT(hits, g.width * g.height / 3);
    const double n = g.width * g.height;
    std::printf(
        "view %d: box chord error RMS %.3f %%, worst %.2f %% of the largest (trilinear 1 voxel %.3f / %.2f %%)\n", view,
        100 * std::sqrt(slice_sq / n) / peak, 100 * slice_worst / peak, 100 * std::sqrt(tri_sq / n) / peak,
        100 * tri_worst / peak);
    // the faces blurred over a voxel, as trilinear's (a ray grazing an edge is off by tens of per
    // cent in both): no worse than it by more than a third
    EXPECT_LT(std::sqrt(slice_sq / n), 1.33 * std::sqrt(tri_sq / n) + 1e-4 * peak) << view;
    EXPECT_LT(slice_worst, 1.33 * tri_worst + 1e-4 * peak) << view;
  }
}

TEST(SliceProjector, IsAsCloseToExactAsTrilinearAtOneVoxelOnSmoothRandomVolumes) {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 3; ++trial) {
    const anatomy::Volume v = random_volume(rng, /*smooth=*/true);
    const AttenuationVolume a(v);
    const DetectorGeometry g = random_geometry(rng, v, 20, 16);
    Image exact, slices, tri;
    exact.resize(g.width, g.height);
    slices.resize(g.width, g.height);
    tri.resize(g.width, g.height);
    SiddonProjector(a, 2).project(g, &exact);
    TrilinearProjector(a, {.step_voxels = 1.0, .skip_empty = true, .threads = 2, .slices = true}).project(g, &slices);
    TrilinearProjector(a, {.step_voxels = 1.0, .skip_empty = true, .threads = 2}).project(g, &tri);
    const Errors es = compare(slices, exact), et = compare(tri, exact);
    std::printf("trial %d: against exact, slices RMSE %.3f %% worst %.2f %%; trilinear 1 voxel %.3f %% / %.2f %%\n",
                trial, 100 * es.rmse_rel, 100 * es.max_rel, 100 * et.rmse_rel, 100 * et.max_rel);
    EXPECT_LT(es.rmse_rel, 0.015) << trial;
    EXPECT_LT(es.max_rel, 0.08) << trial;
    EXPECT_LT(es.rmse_rel, 1.33 * et.rmse_rel) << trial;
  }
}

// the packets and their skipping against one ray at a time and against every plane sampled; the
// packets' paths each run: wide pixels (lanes many voxels apart) gather and walk lane by lane,
// narrow ones (a zoomed detector, lanes within a voxel or two) load rows and walk once for eight
void expect_slices_take_the_same_samples(const AttenuationVolume& a, const DetectorGeometry& g, const char* what) {
  Image skip, full, single;
  for (Image* im : {&skip, &full, &single}) im->resize(g.width, g.height);
  TrilinearProjector(a, {.skip_empty = true, .threads = 2, .slices = true}).project(g, &skip);
  TrilinearProjector(a, {.skip_empty = false, .threads = 2, .slices = true}).project(g, &full);
  TrilinearProjector(a, {.skip_empty = true, .threads = 2, .packets = false, .slices = true}).project(g, &single);
  double top = 0;
  for (const float p : full.pixels) top = std::max<double>(top, p);
  ASSERT_GT(top, 0) << what << ": the rays must cross the volume";
  // empty bricks skipped (per lane, or for a packet by one walk over the bricks near mu) add only
  // zeros; one ray at a time takes the same samples as eight (positions stepped: the last bits)
  EXPECT_LT(compare(skip, full).max_rel, 1e-6) << what;
  EXPECT_LT(compare(single, full).max_rel, 2e-5) << what << ", one ray at a time";
}

TEST(SliceProjector, SkippingAndPacketsTakeTheSameSamples) {
  const ray::SlicePacketCounts before = ray::slice_packet_counts();
  std::mt19937 rng(31);
  for (int trial = 0; trial < 4; ++trial) {
    const anatomy::Volume v = random_volume(rng, /*smooth=*/true);
    AttenuationParams params;
    params.brick_voxels = 2 + trial;  // small bricks: packets wider than a brick walk lane by lane
    const AttenuationVolume a(v, params);
    int empty = 0;
    for (float m : a.brick_max()) empty += m == 0.f;
    ASSERT_GT(empty, 0) << "the test needs empty bricks";
    DetectorGeometry g = random_geometry(rng, v, 37, 11);
    if (trial >= 2) g.pixel_mm *= 2.5;
    expect_slices_take_the_same_samples(a, g, ("wide pixels, trial " + std::to_string(trial)).c_str());
  }
  const ray::SlicePacketCounts wide = ray::slice_packet_counts();
  for (int trial = 0; trial < 6; ++trial) {
    const anatomy::Volume v = random_volume(rng, /*smooth=*/true);
    AttenuationParams params;
    params.brick_voxels = 4;
    const AttenuationVolume a(v, params);
    DetectorGeometry g = random_geometry(rng, v, 64, 8);
    g.pixel_mm *= 0.04;
    expect_slices_take_the_same_samples(a, g, ("narrow pixels, trial " + std::to_string(trial)).c_str());
  }
  const ray::SlicePacketCounts narrow = ray::slice_packet_counts();
  if (!ray::packet_supported()) GTEST_SKIP() << "this CPU has no AVX2: the packets' paths are not used";
  EXPECT_GT(wide.gathered_steps - before.gathered_steps, 0);
  EXPECT_GT(wide.lane_walks - before.lane_walks, 0);
  EXPECT_GT(narrow.row_steps - wide.row_steps, 0);
  EXPECT_GT(narrow.shared_walks - wide.shared_walks, 0);
  std::printf("narrow pixels: %lld steps loaded rows, %lld gathered; %lld packets walked once, %lld lane by lane\n",
              static_cast<long long>(narrow.row_steps - wide.row_steps),
              static_cast<long long>(narrow.gathered_steps - wide.gathered_steps),
              static_cast<long long>(narrow.shared_walks - wide.shared_walks),
              static_cast<long long>(narrow.lane_walks - wide.lane_walks));
}

// the bricks near mu are the bricks holding it dilated by one
TEST(AttenuationVolume, BricksNearMuAreTheNonEmptyOnesDilatedByOne) {
  std::mt19937 rng(4);
  const anatomy::Volume v = random_volume(rng, /*smooth=*/true);
  AttenuationParams params;
  params.brick_voxels = 3;
  const AttenuationVolume a(v, params);
  const auto& n = a.brick_dims();
  const auto at = [&](int i, int j, int k) { return i + n[0] * (j + int64_t(n[1]) * k); };
  int near = 0, far = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        bool want = false;
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int x = i + di, y = j + dj, z = k + dk;
              if (x < 0 || y < 0 || z < 0 || x >= n[0] || y >= n[1] || z >= n[2]) continue;
              want = want || a.brick_max()[at(x, y, z)] > 0.f;
            }
        EXPECT_EQ(a.brick_near()[at(i, j, k)] != 0, want) << i << "," << j << "," << k;
        (want ? near : far) += 1;
      }
  EXPECT_GT(near, 0);
  EXPECT_GT(far, 0) << "the test needs bricks far from mu";
}

TEST(Projectors, RayMissingTheVolumeIsZeroAndWrongImageSizeThrows) {
  std::mt19937 rng(2);
  const anatomy::Volume v = random_volume(rng, true);
  const AttenuationVolume a(v);
  const Vector3d far = v.center_mm() + Vector3d(1000, 0, 0);
  EXPECT_EQ(exact_line_integral(a, far, far + Vector3d(0, 1000, 0)), 0.0);
  DetectorGeometry g = random_geometry(rng, v, 8, 8);
  Image wrong;
  wrong.resize(4, 4);
  EXPECT_THROW(SiddonProjector(a, 1).project(g, &wrong), std::invalid_argument);
  EXPECT_THROW(TrilinearProjector(a).project(g, &wrong), std::invalid_argument);
}

TEST(AttenuationVolume, MuFromHuWithAirThreshold) {
  anatomy::Volume v = anatomy::Volume::make({3, 1, 1}, Vector3d::Ones(), Vector3d::Zero(), anatomy::VoxelType::kInt16);
  v.hu_i16 = {-801, -800, 1000};
  AttenuationParams p;
  p.mu_water_per_mm = 0.025;
  const AttenuationVolume a(v, p);
  EXPECT_EQ(a.mu(0, 0, 0), 0.0f);
  EXPECT_FLOAT_EQ(a.mu(1, 0, 0), 0.025f * 0.2f);
  EXPECT_FLOAT_EQ(a.mu(2, 0, 0), 0.05f);
}

}  // namespace
}  // namespace pcisim::xray
