// The B-mode renderer's behaviour: echo depths on a known phantom (linear and curvilinear),
// attenuation and its compensation, shadowing, the deformation mapping, determinism, settings
// validation, no allocation per frame, and the kidney phantom's cortex echo.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <functional>
#include <numbers>
#include <numeric>
#include <tuple>

#include "anatomy/mesh/kuhn_tetrahedra.h"
#include "anatomy/organ/kidney_phantom.h"
#include "realtime/allocation_count.h"
#include "ultrasound/echo/acoustic_model.h"
#include "ultrasound/echo/point_spread.h"
#include "ultrasound/mapping/tet_locator.h"
#include "ultrasound/render/bmode_renderer.h"

namespace pcisim::ultrasound {
namespace {

using anatomy::Volume;
using Eigen::Vector3d;

// a box x in [-30, 30], y in [-5, 95], z in [-20, 20] mm of `hu_at` at the voxel centres
Volume make_phantom(double h, const std::function<double(const Vector3d&)>& hu_at) {
  const Vector3d lo(-30, -5, -20), hi(30, 95, 20);
  std::array<int64_t, 3> dims{};
  for (int k = 0; k < 3; ++k) dims[k] = static_cast<int64_t>(std::round((hi[k] - lo[k]) / h)) + 1;
  Volume v = Volume::make(dims, Vector3d::Constant(h), lo, anatomy::VoxelType::kFloat32);
  for (int64_t k = 0; k < dims[2]; ++k)
    for (int64_t j = 0; j < dims[1]; ++j)
      for (int64_t i = 0; i < dims[0]; ++i) {
        const Vector3d p = lo + h * Vector3d(i, j, k);
        v.hu_f32[v.linear_index(i, j, k)] = static_cast<float>(hu_at(p));
      }
  return v;
}

constexpr double kSoftHu = 40.0;
constexpr double kSphereR = 8.0, kSphereD = 30.0;  // sphere centre at depth D below the probe at y = 0

const Volume& sphere_phantom() {
  // partial volume: the voxel's inside fraction taken as linear across one voxel of the surface
  constexpr double h = 0.25;
  static const Volume v = make_phantom(h, [](const Vector3d& p) {
    const double inside = std::clamp(0.5 - ((p - Vector3d(0, kSphereD, 0)).norm() - kSphereR) / h, 0.0, 1.0);
    return kSoftHu + 300.0 * inside;
  });
  return v;
}

ProbePose probe_at_top() {
  ProbePose p;
  p.origin_mm = Vector3d(0, 0, 0);
  p.beam = Vector3d::UnitY();
  p.lateral = Vector3d::UnitX();
  return p;
}

UsSettings test_settings(ProbeGeometry g) {
  UsSettings s;
  s.geometry = g;
  s.width_px = 65;  // odd: column 32 is the central scanline
  s.height_px = 256;
  s.depth_mm = 80.0;
  return s;
}

// the depth (mm) of the strongest echo on column c between depths a and b (mm)
double strongest_echo_depth(const BModeRenderer& r, int c, double a, double b) {
  const auto& s = r.settings();
  const double dx = s.depth_mm / s.height_px;
  int best = -1;
  for (int j = 0; j < s.height_px; ++j) {
    const double d = (j + 0.5) * dx;
    if (d < a || d > b) continue;
    if (best < 0 || r.echo_intensity()[j * s.width_px + c] > r.echo_intensity()[best * s.width_px + c]) best = j;
  }
  return (best + 0.5) * dx;
}

double mean_rows(const BModeImage& im, int r0, int r1, int c0, int c1) {
  double s = 0;
  int n = 0;
  for (int r = r0; r < r1; ++r)
    for (int c = c0; c < c1; ++c, ++n) s += im.pixels[r * im.width + c];
  return s / n;
}

// the sphere's far wall where its echo arrives: the scanner draws depth as c0 t / 2, and sound
// crosses the sphere (340 HU) faster than c0, so it shows nearer than D + R; the geometry scaled
// by k along the beam
double far_wall_shown(double k) {
  return k * (kSphereD - kSphereR) + 2.0 * k * kSphereR * kNominalSpeedMS / speed_of_sound_m_s(kSoftHu + 300.0);
}

TEST(BModeRenderer, SphereEchoesLieAtItsNearAndFarWallLinearAndCurvilinear) {
  for (ProbeGeometry g : {ProbeGeometry::kLinear, ProbeGeometry::kCurvilinear}) {
    BModeRenderer r(sphere_phantom(), test_settings(g));
    r.render(probe_at_top(), 1);
    const double dx = r.settings().depth_mm / r.settings().height_px;
    const int centre = r.settings().width_px / 2;
    EXPECT_NEAR(strongest_echo_depth(r, centre, 1.0, 79.0), kSphereD - kSphereR, dx) << static_cast<int>(g);
    EXPECT_NEAR(strongest_echo_depth(r, centre, kSphereD, 79.0), far_wall_shown(1.0), dx) << static_cast<int>(g);
    // the central scanline's pixel centres map along the beam
    EXPECT_NEAR((pixel_to_world(r.settings(), probe_at_top(), centre, 10) - Vector3d(0, 10.5 * dx, 0)).norm(), 0.0,
                1e-9);
  }
}

TEST(BModeRenderer, CurvilinearDisplayIsTheScanConvertedFan) {
  const UsSettings s = test_settings(ProbeGeometry::kCurvilinear);
  const ProbePose pose = probe_at_top();
  // the display map and the beam map name the same world point
  int inside = 0;
  for (int r = 0; r < s.height_px; r += 7)
    for (int c = 0; c < s.width_px; c += 3) {
      double bc = 0, br = 0;
      if (!display_to_beam(s, c, r, &bc, &br)) continue;
      ++inside;
      EXPECT_NEAR((display_pixel_to_world(s, pose, c, r) - pixel_to_world(s, pose, bc, br)).norm(), 0.0, 1e-9);
    }
  EXPECT_GT(inside, 100);
  double bc = 0, br = 0;
  EXPECT_FALSE(display_to_beam(s, 0, 0, &bc, &br));  // a corner above the fan's edge
  // the sphere's near wall is bright in the display image on its central column, the tissue above grey
  BModeRenderer r(sphere_phantom(), s);
  const BModeImage& im = r.render(pose, 1);
  const int c = s.width_px / 2;
  int wall = -1;
  double best = 1e9;
  for (int row = 0; row < s.height_px; ++row) {
    const double e = std::abs(display_pixel_to_world(s, pose, c, row).y() - (kSphereD - kSphereR));
    if (e < best) best = e, wall = row;
  }
  EXPECT_GT(im.pixels[wall * im.width + c], mean_rows(im, wall - 30, wall - 5, c - 2, c + 3) + 40.0);
  EXPECT_EQ(im.pixels[0], 0);  // outside the fan: black
}

TEST(BModeRenderer, UniformMediumDimsWithDepthAndMatchingTgcFlattensIt) {
  const Volume v = make_phantom(1.0, [](const Vector3d&) { return kSoftHu; });
  UsSettings s = test_settings(ProbeGeometry::kLinear);
  s.tgc_db_per_cm = 0.0;
  s.gain_db = 30.0;  // diffuse soft tissue at ~-42 dB: keep both bands above black
  BModeRenderer plain(v, s);
  const BModeImage a = plain.render(probe_at_top(), 3);
  const double top = mean_rows(a, 16, 64, 0, s.width_px), bottom = mean_rows(a, 192, 240, 0, s.width_px);
  // 2 alpha f = 5.4 dB/cm over 5.6 cm between the bands: ~30 dB, ~128 grey levels at 60 dB range
  EXPECT_GT(top - bottom, 90.0);
  s.tgc_db_per_cm = 2.0 * s.attenuation_db_per_cm_mhz * s.frequency_mhz;
  BModeRenderer compensated(v, s);
  const BModeImage& b = compensated.render(probe_at_top(), 3);
  EXPECT_NEAR(mean_rows(b, 16, 64, 0, s.width_px), mean_rows(b, 192, 240, 0, s.width_px), 3.0);
}

TEST(BModeRenderer, BoneShadowsWhatLiesBehindIt) {
  const Volume v = make_phantom(
      0.5, [](const Vector3d& p) { return std::abs(p.x()) < 5.0 && p.y() > 15.0 && p.y() < 20.0 ? 1000.0 : kSoftHu; });
  const UsSettings s = test_settings(ProbeGeometry::kLinear);  // 40 mm wide: columns 0-9 are at |x| > 14 mm
  BModeRenderer r(v, s);
  const BModeImage& im = r.render(probe_at_top(), 5);
  const int r0 = 30 * 256 / 80, r1 = 70 * 256 / 80;
  const double behind = mean_rows(im, r0, r1, 28, 37), beside = mean_rows(im, r0, r1, 0, 9);
  EXPECT_LT(behind, beside - 50.0) << behind << " vs " << beside;
}

// Kuhn cubes of edge h over the phantom's box (offset so no grid plane holds the image plane)
TetSnapshot grid_mesh(double h) {
  const Vector3d lo(-30.37, -5.37, -20.37);
  const Eigen::Vector3i n(7, 11, 5);
  auto id = [&](int i, int j, int k) { return i + (n[0] + 1) * (j + (n[1] + 1) * k); };
  TetSnapshot m;
  m.rest_mm.resize(3, (n[0] + 1) * (n[1] + 1) * (n[2] + 1));
  for (int k = 0; k <= n[2]; ++k)
    for (int j = 0; j <= n[1]; ++j)
      for (int i = 0; i <= n[0]; ++i) m.rest_mm.col(id(i, j, k)) = lo + h * Vector3d(i, j, k);
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        for (const auto& t : anatomy::kKuhnTetrahedra) {
          std::array<int, 4> tet;
          for (int v = 0; v < 4; ++v) tet[v] = id(i + (t[v] & 1), j + ((t[v] >> 1) & 1), k + ((t[v] >> 2) & 1));
          m.tets.push_back(tet);
        }
  m.current_mm = m.rest_mm;
  return m;
}

TEST(BModeRenderer, TranslatedMeshAndProbeGiveTheUndeformedImage) {
  const UsSettings s = test_settings(ProbeGeometry::kLinear);
  BModeRenderer plain(sphere_phantom(), s);
  const BModeImage reference = plain.render(probe_at_top(), 11);
  TetSnapshot mesh = grid_mesh(10.0);
  const Vector3d t(3.1, -2.2, 1.7);
  mesh.current_mm = mesh.rest_mm.colwise() + t;
  ProbePose moved = probe_at_top();
  moved.origin_mm += t;
  BModeRenderer deformed(sphere_phantom(), s);
  const BModeImage& im = deformed.render(moved, 11, &mesh);
  int equal = 0, worst = 0;
  for (size_t i = 0; i < im.pixels.size(); ++i) {
    const int d = std::abs(im.pixels[i] - reference.pixels[i]);
    equal += d == 0;
    worst = std::max(worst, d);
  }
  // the same rest points up to rounding of the barycentric coordinates
  EXPECT_LE(worst, 1);
  EXPECT_GE(equal, static_cast<int>(0.99 * im.pixels.size()));
}

TEST(BModeRenderer, MeshCompressedAlongTheBeamMovesTheEchoDepth) {
  const UsSettings s = test_settings(ProbeGeometry::kLinear);
  TetSnapshot mesh = grid_mesh(10.0);
  const double k = 0.8;  // y -> k y about the probe face (y = 0): affine, so the barycentric map is exact
  mesh.current_mm.row(1) *= k;
  BModeRenderer r(sphere_phantom(), s);
  r.render(probe_at_top(), 2, &mesh);
  const double dx = s.depth_mm / s.height_px;
  EXPECT_NEAR(strongest_echo_depth(r, s.width_px / 2, 1.0, 79.0), k * (kSphereD - kSphereR), dx);
  EXPECT_NEAR(strongest_echo_depth(r, s.width_px / 2, k * kSphereD, 79.0), far_wall_shown(k), dx);
}

TEST(BModeRenderer, SameSeedSameImageAndNothingAllocatedPerFrame) {
  const UsSettings s = test_settings(ProbeGeometry::kCurvilinear);
  TetSnapshot mesh = grid_mesh(10.0);
  BModeRenderer r(sphere_phantom(), s);
  const BModeImage a = r.render(probe_at_top(), 42, &mesh);
  mesh.current_mm.row(1) *= 0.9;
  long allocations = -1;
  {
    realtime::AllocationCount count;
    r.render(probe_at_top(), 42, &mesh);
    mesh.current_mm = mesh.rest_mm;
    r.render(probe_at_top(), 42, &mesh);
    allocations = count.allocations();
  }
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(r.render(probe_at_top(), 42, &mesh).pixels, a.pixels);
  EXPECT_NE(r.render(probe_at_top(), 43, &mesh).pixels, a.pixels);
}

// the lookup that tries the last tet first finds what the plain lookup finds, along rays through
// a deformed grid (the hint kept from sample to sample, as a scanline keeps it)
TEST(TetLocator, TheHintedLookupIsThePlainOne) {
  TetSnapshot mesh = grid_mesh(10.0);
  for (int v = 0; v < mesh.current_mm.cols(); ++v)
    mesh.current_mm.col(v) += Vector3d(0.3 * std::sin(0.1 * v), 0.1 * mesh.rest_mm(1, v), 0.2 * std::cos(0.07 * v));
  TetLocator locator;
  locator.build(mesh);
  int found = 0, hinted = 0;
  for (double x = -25.0; x <= 25.0; x += 2.5) {
    int hint = -1;
    for (double y = -2.0; y <= 90.0; y += 0.37) {
      const Vector3d p(x, y, 0.3 * x);
      Vector3d a, b;
      const bool plain = locator.to_rest(p, &a), with = locator.to_rest(p, &b, &hint);
      ASSERT_EQ(plain, with) << p.transpose();
      if (!plain) continue;
      ++found;
      hinted += hint >= 0;
      EXPECT_LT((a - b).norm(), 1e-9) << p.transpose();
    }
  }
  EXPECT_GT(found, 1000);
  EXPECT_EQ(hinted, found);
}

// a frame spread over threads is the one thread's frame, bit for bit, and allocates nothing
TEST(BModeRenderer, ThreadsGiveTheSameFrameAndAllocateNothing) {
  UsSettings s = test_settings(ProbeGeometry::kCurvilinear);
  TetSnapshot mesh = grid_mesh(10.0);
  mesh.current_mm.row(1) *= 0.9;
  BModeRenderer one(sphere_phantom(), s);
  const BModeImage a = one.render(probe_at_top(), 42, &mesh);
  const std::vector<float> echo = one.echo_intensity();
  s.threads = 3;
  BModeRenderer three(sphere_phantom(), s);
  three.render(probe_at_top(), 42, &mesh);
  long allocations = -1;
  {
    realtime::AllocationCount count;
    three.render(probe_at_top(), 42, &mesh);
    allocations = count.allocations();
  }
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(three.render(probe_at_top(), 42, &mesh).pixels, a.pixels);
  EXPECT_EQ(three.echo_intensity(), echo);
  s.threads = 0;
  EXPECT_THROW(BModeRenderer(sphere_phantom(), s), std::invalid_argument);
}

// the probe's depth and gain knobs: turned on a running renderer, the frame is the one a renderer
// built with those settings draws (the sphere's near wall at its depth in either), nothing is
// allocated, and an out-of-range knob is refused naming it, changing nothing
TEST(BModeRenderer, DepthAndGainTurnedAtRunTimeGiveTheFrameOfThoseSettings) {
  for (ProbeGeometry g : {ProbeGeometry::kLinear, ProbeGeometry::kCurvilinear}) {
    BModeRenderer r(sphere_phantom(), test_settings(g));
    r.render(probe_at_top(), 7);
    UsSettings shallow = test_settings(g);
    shallow.depth_mm = 50.0;
    shallow.gain_db = 12.0;
    long allocations = -1;
    {
      realtime::AllocationCount count;
      r.set_imaging(shallow.depth_mm, shallow.gain_db);
      r.render(probe_at_top(), 7);
      allocations = count.allocations();
    }
    EXPECT_EQ(allocations, 0) << static_cast<int>(g);
    BModeRenderer fresh(sphere_phantom(), shallow);
    EXPECT_EQ(r.render(probe_at_top(), 7).pixels, fresh.render(probe_at_top(), 7).pixels) << static_cast<int>(g);
    const double dx = shallow.depth_mm / shallow.height_px;
    EXPECT_NEAR(strongest_echo_depth(r, shallow.width_px / 2, 1.0, 49.0), kSphereD - kSphereR, dx);
    // gain brightens: the same depth 12 dB lower is darker on average
    const double bright = mean_rows(r.beam_image(), 0, shallow.height_px, 0, shallow.width_px);
    r.set_imaging(shallow.depth_mm, 0.0);
    r.render(probe_at_top(), 7);
    EXPECT_LT(mean_rows(r.beam_image(), 0, shallow.height_px, 0, shallow.width_px) + 1.0, bright);
    for (auto [depth, gain, field] :
         {std::tuple{0.0, 0.0, "depth_mm"}, std::tuple{301.0, 0.0, "depth_mm"}, std::tuple{50.0, 61.0, "gain_db"}}) {
      try {
        r.set_imaging(depth, gain);
        ADD_FAILURE() << "accepted depth " << depth << " gain " << gain;
      } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
      }
      EXPECT_EQ(r.settings().depth_mm, 50.0);
      EXPECT_EQ(r.settings().gain_db, 0.0);
    }
  }
}

TEST(BModeRenderer, BadSettingsThrowNamingTheField) {
  const auto throws_naming = [](UsSettings s, const std::string& field) {
    try {
      validate(s);
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << field << " was accepted";
  };
  UsSettings s;
  s.depth_mm = -1.0;
  throws_naming(s, "depth_mm");
  s = {};
  s.width_px = 3;
  throws_naming(s, "width_px");
  s = {};
  s.frequency_mhz = NAN;
  throws_naming(s, "frequency_mhz");
  s = {};
  s.dynamic_range_db = 0.0;
  throws_naming(s, "dynamic_range_db");
  s = {};
  s.geometry = ProbeGeometry::kCurvilinear;
  s.fan_angle_deg = 180.0;
  throws_naming(s, "fan_angle_deg");
  s = {};
  s.width_mm = 0.0;
  throws_naming(s, "width_mm");
  EXPECT_THROW(BModeRenderer(sphere_phantom(), s), std::invalid_argument);
  ProbePose p;
  p.lateral = p.beam;
  EXPECT_THROW(validate(p), std::invalid_argument);
}

TEST(AcousticModel, ImpedanceAndReflectionFollowTheirEquations) {
  EXPECT_NEAR(impedance_mrayl(40.0), 1.04 * 1.540, 1e-12);
  EXPECT_NEAR(reflection(1.0, 3.0), 0.25, 1e-15);
  EXPECT_GT(reflection(impedance_mrayl(40.0), impedance_mrayl(-1000.0)), 0.998);  // tissue / air
  // the tissue's scatterers: circular complex Gaussian, E a = 0, E|a|^2 = 1, so |a|^2 is
  // exponential: P(|a|^2 > 1) = 1/e
  std::complex<double> mean = 0;
  double power = 0, above = 0, re2 = 0, im2 = 0;
  constexpr int kN = 20000;
  for (int i = 0; i < kN; ++i) {
    const std::complex<double> a = scatterer(9, i % 100, i / 100, -i % 7);
    mean += a / double(kN);
    power += std::norm(a) / kN;
    above += (std::norm(a) > 1.0) / double(kN);
    re2 += a.real() * a.real() / kN;
    im2 += a.imag() * a.imag() / kN;
  }
  EXPECT_LT(std::abs(mean), 0.02);
  EXPECT_NEAR(power, 1.0, 0.03);
  EXPECT_NEAR(re2, 0.5, 0.02);
  EXPECT_NEAR(im2, 0.5, 0.02);
  EXPECT_NEAR(above, std::exp(-1.0), 0.015);
  EXPECT_NE(scatterer(9, 1, 2, 3), scatterer(10, 1, 2, 3));
}

// the scanline's cache of a lattice cell's corners (kept across a step to a face neighbour, up
// or down any axis; refetched on any other move) gives the field bit for bit
TEST(AcousticModel, TheCachedScattererFieldIsTheFieldBitForBit) {
  ScattererCell cell;
  double u[3] = {-3.7, 12.2, 0.4};
  uint64_t state = 12345;
  auto next = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  int hits = 0;
  for (int n = 0; n < 5000; ++n) {
    const double kind = next();
    if (kind < 0.7) {
      for (double& x : u) x += 0.3 * (next() - 0.5);  // a sample's step: often the same cell
    } else if (kind < 0.95) {
      u[static_cast<int>(next() * 3)] += next() < 0.5 ? 1.0 : -1.0;  // a face neighbour
    } else {
      for (double& x : u) x += 10.0 * (next() - 0.5);  // anywhere
    }
    const int64_t before[3] = {cell.index[0], cell.index[1], cell.index[2]};
    const std::complex<float> cached = scatterer_field(9, u, &cell), plain = scatterer_field(9, u);
    ASSERT_EQ(cached, plain) << n;
    hits += before[0] == cell.index[0] && before[1] == cell.index[1] && before[2] == cell.index[2];
  }
  EXPECT_GT(hits, 1000);  // the cache was used, not refilled every time
}

TEST(BModeRenderer, KidneyCortexEchoWhereThePhantomSaysAndPng) {
  const anatomy::KidneyPhantom kidney = anatomy::make_kidney_phantom();
  UsSettings s;
  BModeRenderer r(kidney.ct, s);
  ProbePose p;
  p.origin_mm = Vector3d(0, kidney.ct.origin_mm.y(), 0);
  p.beam = Vector3d::UnitY();
  p.lateral = Vector3d::UnitZ();
  const BModeImage& im = r.render(p, 1);
  // the anterior surface along -y from the organ's centre, shown where its echo arrives through
  // the fat above it (1450 m/s: deeper than it is by c0 / c_fat)
  const double surface_y = -anatomy::kidney_radius_mm(kidney.spec, -Vector3d::UnitY());
  const double expected = (surface_y - p.origin_mm.y()) * kNominalSpeedMS / speed_of_sound_m_s(anatomy::kKidneyFatHu);
  const int c = s.width_px / 2;
  const double found = strongest_echo_depth(r, c, 1.0, expected + 3.0);
  EXPECT_NEAR(found, expected, kidney.ct.spacing_mm.maxCoeff());
  const int row = static_cast<int>(found / s.depth_mm * s.height_px);
  EXPECT_GT(im.pixels[row * im.width + c], mean_rows(im, 2, row - 4, 0, im.width) + 40.0);
  const auto dir = std::filesystem::temp_directory_path() / ("pcisim-us-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  write_png((dir / "kidney.png").string(), im);
  EXPECT_GT(std::filesystem::file_size(dir / "kidney.png"), 1000u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pcisim::ultrasound

namespace pcisim::ultrasound {
namespace {

// a cube of tets over [-40, 40] x [-10, 90] x [-30, 30] mm (Kuhn, 4 x 5 x 3 cubes of 20 mm)
TetSnapshot cube_mesh() {
  TetSnapshot m;
  const int nx = 4, ny = 5, nz = 3;
  m.rest_mm.resize(3, (nx + 1) * (ny + 1) * (nz + 1));
  auto id = [&](int i, int j, int k) { return i + (nx + 1) * (j + (ny + 1) * k); };
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) m.rest_mm.col(id(i, j, k)) = Vector3d(-40 + 20 * i, -10 + 20 * j, -30 + 20 * k);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& t : anatomy::kKuhnTetrahedra) {
          std::array<int, 4> tet{};
          for (int v = 0; v < 4; ++v) tet[v] = id(i + (t[v] & 1), j + ((t[v] >> 1) & 1), k + ((t[v] >> 2) & 1));
          m.tets.push_back(tet);
        }
  m.current_mm = m.rest_mm;
  return m;
}

double fraction_equal(const BModeImage& a, const BModeImage& b) {
  size_t same = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) same += a.pixels[i] == b.pixels[i];
  return static_cast<double>(same) / static_cast<double>(a.pixels.size());
}

// speckle belongs to the tissue: tissue and probe moved together give the same image; the probe
// moved over still tissue gives another pattern (hashing the pixel, as before, gave the same)
TEST(BModeRenderer, SpeckleMovesWithTheTissueAndDoesNotFlicker) {
  const Volume ct = make_phantom(1.0, [](const Vector3d&) { return kSoftHu; });  // speckle only
  UsSettings s = test_settings(ProbeGeometry::kLinear);
  s.depth_mm = 60.0;
  BModeRenderer r(ct, s);
  TetSnapshot mesh = cube_mesh();
  r.set_mesh(mesh);
  const ProbePose p0 = probe_at_top();
  const BModeImage a = r.render(p0, 3, &mesh);
  const BModeImage again = r.render(p0, 3, &mesh);
  EXPECT_EQ(fraction_equal(a, again), 1.0) << "the same tissue, the same frame";

  const Vector3d d(3.1, 1.7, 0.0);  // within the image plane: lateral and deeper
  TetSnapshot moved = mesh;
  moved.current_mm.colwise() += d;
  ProbePose p1 = p0;
  p1.origin_mm += d;
  const BModeImage with_tissue = r.render(p1, 3, &moved);
  const BModeImage over_still = r.render(p1, 3, &mesh);
  const double carried = fraction_equal(a, with_tissue), slid = fraction_equal(a, over_still);
  std::printf("pixels equal: probe and tissue moved together %.4f, probe over still tissue %.4f\n", carried, slid);
  EXPECT_GT(carried, 0.99);
  EXPECT_LT(slid, 0.5);
}

// --- image formation (issue #32): speckle from scatterers under the PSF, time of flight ---

// a speckle-only frame whose PSF is resolved by the samples: uniform soft tissue, no attenuation,
// 3.5 MHz, focus at 15 mm, samples 0.059 mm apart, scanlines 0.078 mm, scatterer cells 0.04 mm
UsSettings speckle_settings() {
  UsSettings s;
  s.width_mm = 40.0;
  s.width_px = 512;
  s.depth_mm = 30.0;
  s.height_px = 512;
  s.frequency_mhz = 3.5;
  s.bandwidth = 0.5;
  s.f_number = 2.0;
  s.focus_mm = 15.0;
  s.attenuation_db_per_cm_mhz = 0.0;
  s.tgc_db_per_cm = 0.0;
  s.speckle_cell_mm = 0.04;
  return s;
}

const Volume& uniform_soft() {
  static const Volume v = make_phantom(1.0, [](const Vector3d&) { return kSoftHu; });
  return v;
}

// the intensity's normalised autocorrelation over rows [r0, r1) x columns [c0, c1) at a lag along
// the beam (dr) or across it (dc)
double intensity_acf(const std::vector<float>& im, int w, int r0, int r1, int c0, int c1, int dr, int dc) {
  double mean = 0;
  int n = 0;
  for (int r = r0; r < r1; ++r)
    for (int c = c0; c < c1; ++c, ++n) mean += im[r * w + c];
  mean /= n;
  double num = 0, var = 0;
  for (int r = r0; r < r1; ++r)
    for (int c = c0; c < c1; ++c) {
      const double a = im[r * w + c] - mean;
      var += a * a;
      num += a * (im[(r + dr) * w + c + dc] - mean);
    }
  return num / var;
}

// the lag (fractional, linear between lags) where the autocorrelation first falls to 1/2, doubled
double acf_fwhm_lags(const std::function<double(int)>& acf) {
  double prev = 1.0;
  for (int lag = 1; lag < 60; ++lag) {
    const double a = acf(lag);
    if (a <= 0.5) return 2.0 * (lag - 1 + (prev - 0.5) / (prev - a));
    prev = a;
  }
  return 120.0;
}

// fully developed speckle: the envelope is Rayleigh, mean / std = sqrt(pi / (4 - pi)) = 1.91
// [Wagner et al. 1983]; the per-pixel intensity of the old model was also exponential, so this
// checks the pipeline (envelope before log compression, a uniform mean over depth), the next
// test the grain
TEST(BModeImageFormation, SpeckleInUniformTissueIsFullyDeveloped) {
  const UsSettings s = speckle_settings();
  BModeRenderer r(uniform_soft(), s);
  r.render(probe_at_top(), 5);
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int row = 50; row < 460; ++row)
    for (int c = 40; c < s.width_px - 40; ++c, ++n) {
      const double e = std::sqrt(r.echo_intensity()[row * s.width_px + c]);
      sum += e;
      sum2 += e * e;
    }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  std::printf("envelope mean / std %.3f (Rayleigh 1.913); mean intensity %.3g (backscatter %.3g)\n", mean / sd,
              sum2 / n, backscatter(kSoftHu));
  EXPECT_NEAR(mean / sd, std::sqrt(std::numbers::pi / (4.0 - std::numbers::pi)), 0.1);
  // the scatterers are scaled so that the diffuse echo's mean is the tissue's backscatter
  EXPECT_NEAR(sum2 / n / backscatter(kSoftHu), 1.0, 0.1);
}

// the speckle's grain is the PSF's: for a Gaussian PSF the intensity's autocorrelation has the
// amplitude PSF's FWHM along each axis [Wagner 1983]; the PSF from point_spread.h's formulas
TEST(BModeImageFormation, SpeckleSizeIsThePointSpreadFunctions) {
  const UsSettings s = speckle_settings();
  BModeRenderer r(uniform_soft(), s);
  r.render(probe_at_top(), 6);
  const auto& im = r.echo_intensity();
  const int w = s.width_px;
  const double dx = s.depth_mm / s.height_px, dl = s.width_mm / s.width_px;
  const double axial_mm =
      dx * acf_fwhm_lags([&](int lag) { return intensity_acf(im, w, 60, 400, 40, w - 40, lag, 0); });
  // laterally within 1.5 mm of the focus, where the PSF's width varies by under 10 %
  const int r0 = static_cast<int>(13.5 / dx), r1 = static_cast<int>(16.5 / dx);
  const double lateral_mm =
      dl * acf_fwhm_lags([&](int lag) { return intensity_acf(im, w, r0, r1, 40, w - 80, 0, lag); });
  const double axial_psf = kFwhmPerSigma * axial_psf_sigma_mm(s.frequency_mhz, s.bandwidth);
  double lateral_psf = 0;
  for (int row = r0; row < r1; ++row) lateral_psf += kFwhmPerSigma * lateral_psf_sigma_mm(s, (row + 0.5) * dx);
  lateral_psf /= (r1 - r0);
  std::printf("speckle FWHM axial %.3f mm (PSF %.3f), lateral %.3f mm (PSF %.3f)\n", axial_mm, axial_psf, lateral_mm,
              lateral_psf);
  EXPECT_NEAR(axial_mm / axial_psf, 1.0, 0.2);
  EXPECT_NEAR(lateral_mm / lateral_psf, 1.0, 0.2);
  EXPECT_GT(lateral_mm, 1.3 * axial_mm) << "real speckle is elongated laterally";
}

// time of flight: 20 mm of fat (-100 HU, 1450 m/s) over soft tissue (40 HU, 1540 m/s) with a
// denser layer (300 HU) from 30 mm. The scanner draws depth as 1540 m/s x t / 2, so the fat's
// far boundary shows at 20 x 1540 / 1450 = 21.24 mm and the dense layer at 31.24 mm (not 20, 30)
TEST(BModeImageFormation, ABoundaryBehindFatShowsWhereItsEchoArrives) {
  const Volume ct = make_phantom(0.25, [](const Vector3d& p) {
    const double fat = std::clamp(0.5 - (p.y() - 20.0) / 0.25, 0.0, 1.0);
    const double dense = std::clamp(0.5 + (p.y() - 30.0) / 0.25, 0.0, 1.0);
    return -100.0 * fat + kSoftHu * (1.0 - fat) + (300.0 - kSoftHu) * dense;
  });
  UsSettings s = test_settings(ProbeGeometry::kLinear);
  s.depth_mm = 40.0;
  s.height_px = 512;
  const double dx = s.depth_mm / s.height_px;
  BModeRenderer r(ct, s);
  r.render(probe_at_top(), 4);
  const double fat_end = 20.0 * kNominalSpeedMS / speed_of_sound_m_s(-100.0);
  const double dense = fat_end + 10.0 * kNominalSpeedMS / speed_of_sound_m_s(kSoftHu);
  std::printf("fat's end shown at %.3f mm (arrival %.3f), dense layer at %.3f mm (arrival %.3f)\n",
              strongest_echo_depth(r, 32, 15.0, 25.0), fat_end, strongest_echo_depth(r, 32, 26.0, 36.0), dense);
  EXPECT_NEAR(strongest_echo_depth(r, 32, 15.0, 25.0), fat_end, dx);
  EXPECT_NEAR(strongest_echo_depth(r, 32, 26.0, 36.0), dense, dx);
}

// the scatterers are the tissue's: the tissue alone moved under a still probe by d within the
// image plane, the speckle pattern moves by d (the best match of the two frames' intensities
// within one pixel of d along each axis)
TEST(BModeImageFormation, TheSpeckleFollowsTheTissuesDisplacement) {
  UsSettings s = test_settings(ProbeGeometry::kLinear);
  s.width_px = 256;  // 0.156 mm, as the samples (40 mm / 256)
  s.depth_mm = 40.0;
  s.speckle_cell_mm = 0.4;  // two samples and more: the field is followed between them
  s.attenuation_db_per_cm_mhz = 0.0;
  BModeRenderer r(uniform_soft(), s);
  TetSnapshot mesh = grid_mesh(10.0);
  r.render(probe_at_top(), 8, &mesh);
  const std::vector<float> before = r.echo_intensity();
  const Vector3d d(1.1, 0.9, 0.0);  // lateral, deeper
  mesh.current_mm = mesh.rest_mm.colwise() + d;
  r.render(probe_at_top(), 8, &mesh);
  const std::vector<float>& after = r.echo_intensity();
  const int w = s.width_px;
  const double dl = s.width_mm / s.width_px, dx = s.depth_mm / s.height_px;
  int best_dr = 0, best_dc = 0;
  double best = -1e300;
  for (int dr = -12; dr <= 12; ++dr)
    for (int dc = -12; dc <= 12; ++dc) {
      double num = 0;
      for (int row = 40; row < 200; ++row)
        for (int c = 30; c < w - 30; ++c) num += before[row * w + c] * after[(row + dr) * w + c + dc];
      if (num > best) {
        best = num;
        best_dr = dr;
        best_dc = dc;
      }
    }
  std::printf("speckle moved %d rows, %d scanlines (tissue: %.2f, %.2f)\n", best_dr, best_dc, d.y() / dx, d.x() / dl);
  EXPECT_LE(std::abs(best_dr - d.y() / dx), 1.0);
  EXPECT_LE(std::abs(best_dc - d.x() / dl), 1.0);
}

// the kidney pressed as pcisim-us-kidney presses it (its tets, the organ's top pushed 3 mm at the
// middle): the vacated space reads the undeformed CT, so the impedance jumps within a sample
// where the pushed surface meets it; every echo stays finite (a boundary whose steepest sample
// had equal Z either side gave 0 / 0 for its angle, and the NaN spread through both convolutions
// into a black block)
TEST(BModeImageFormation, APressedKidneyEchoesFinitelyEverywhere) {
  const anatomy::KidneyPhantom kidney = anatomy::make_kidney_phantom();
  const anatomy::KidneySpec& spec = kidney.spec;
  constexpr double h = 11.0;
  const Vector3d lo = -spec.semi_axes_mm - Vector3d::Constant(h);
  Eigen::Vector3i n;
  for (int k = 0; k < 3; ++k) n[k] = static_cast<int>(std::ceil(2.0 * (spec.semi_axes_mm[k] + h) / h));
  auto id = [&](int i, int j, int k) { return i + (n[0] + 1) * (j + (n[1] + 1) * k); };
  TetSnapshot m;
  m.rest_mm.resize(3, (n[0] + 1) * (n[1] + 1) * (n[2] + 1));
  for (int k = 0; k <= n[2]; ++k)
    for (int j = 0; j <= n[1]; ++j)
      for (int i = 0; i <= n[0]; ++i) m.rest_mm.col(id(i, j, k)) = lo + h * Vector3d(i, j, k);
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        for (const auto& t : anatomy::kKuhnTetrahedra) {
          std::array<int, 4> tet{};
          Vector3d c = Vector3d::Zero();
          for (int v = 0; v < 4; ++v) {
            tet[v] = id(i + (t[v] & 1), j + ((t[v] >> 1) & 1), k + ((t[v] >> 2) & 1));
            c += 0.25 * m.rest_mm.col(tet[v]);
          }
          if (anatomy::kidney_normalised_radius(spec, c) < 1.0) m.tets.push_back(tet);
        }
  m.current_mm = m.rest_mm;
  const double a_y = spec.semi_axes_mm.y();
  for (int v = 0; v < m.rest_mm.cols(); ++v) {
    const Vector3d r = m.rest_mm.col(v);
    const double g = std::exp(-(r.x() * r.x() + r.z() * r.z()) / (2.0 * 20.0 * 20.0));
    m.current_mm.col(v) = r + Vector3d(0.0, 3.0 * g * std::clamp((a_y - r.y()) / (2.0 * a_y), 0.0, 1.0), 0.0);
  }
  UsSettings s;
  s.width_mm = 50.0;
  s.height_px = 512;
  BModeRenderer r(kidney.ct, s);
  ProbePose p;
  p.origin_mm = Vector3d(0, kidney.ct.origin_mm.y(), 0);
  p.lateral = Vector3d::UnitZ();
  r.render(p, 7, &m);
  const auto& e = r.echo_intensity();
  EXPECT_EQ(std::count_if(e.begin(), e.end(), [](float v) { return !std::isfinite(v); }), 0);
}

// the specular echo falls off as cos^n with the angle between the beam and the boundary's normal:
// fluid (0 HU) over dense tissue (300 HU) across the plane y = 30 + x, 45 degrees to the beam in
// the image plane (scanlines as far apart as samples, so the gradient's two differences are
// alike); its echo peaks, n = 6 against n = 0, average cos^6(45) = 1/8 as bright over the
// scanlines (the scatterers are 12 dB below the echo at n = 6, 21 dB at n = 0; the largest sample
// over a window leans a little above the echo: 0.1346 measured; n / 4 would give 0.35, n 0.016)
TEST(BModeImageFormation, AnObliqueBoundaryEchoesLessByTheSpecularLobe) {
  const Volume ct = make_phantom(0.25, [](const Vector3d& p) {
    const double across = (p.y() - 30.0 - p.x()) / std::sqrt(2.0);
    return 300.0 * std::clamp(0.5 + across / 0.25, 0.0, 1.0);
  });
  UsSettings s = test_settings(ProbeGeometry::kLinear);
  s.width_px = 128;  // 0.3125 mm, as the samples (80 mm / 256)
  s.attenuation_db_per_cm_mhz = 0.0;
  s.tgc_db_per_cm = 0.0;
  const double dx = s.depth_mm / s.height_px;
  auto mean_peak = [&](double n) {
    s.specular_exponent = n;
    BModeRenderer r(ct, s);
    r.render(probe_at_top(), 3);
    double sum = 0;
    for (int c = 10; c < s.width_px - 10; ++c) {
      const double x = ((c + 0.5) / s.width_px - 0.5) * s.width_mm;
      float best = 0;
      for (int j = 0; j < s.height_px; ++j)
        if (std::abs((j + 0.5) * dx - (30.0 + x)) < 3.0) best = std::max(best, r.echo_intensity()[j * s.width_px + c]);
      sum += best;
    }
    return sum;
  };
  const double ratio = mean_peak(6.0) / mean_peak(0.0);
  std::printf("oblique boundary, n = 6 over n = 0: %.4f (cos^6 45 = 0.125)\n", ratio);
  EXPECT_NEAR(ratio, 0.125, 0.02);
}

}  // namespace
}  // namespace pcisim::ultrasound
