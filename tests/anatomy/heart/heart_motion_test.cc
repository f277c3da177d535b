// The motion sequence: file round trip, bad files name what is wrong, interpolation in space
// and time, and the built-in synthetic sequence's physiology (EF, systole, thickening, shortening).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "anatomy/heart/heart_frame.h"
#include "anatomy/heart/heart_mesh.h"
#include "anatomy/heart/heart_motion.h"
#include "anatomy/heart/synthetic_heart_motion.h"
#include "anatomy/heart/template_heart_surface.h"

namespace pcisim::anatomy {
namespace {

using Eigen::Vector3d;

// a small sequence whose displacement is linear in position per frame (trilinear reproduces it)
HeartMotion small_motion() {
  MotionGrid g;
  g.origin_m = {-0.01, -0.02, 0.0};
  g.spacing_m = {0.01, 0.02, 0.005};
  g.dims = {3, 3, 2};
  const int frames = 4;
  std::vector<float> data;
  for (int f = 0; f < frames; ++f)
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
          const Vector3d p = g.origin_m + g.spacing_m.cwiseProduct(Vector3d(i, j, k));
          const Vector3d d = 0.001 * (f + 1) * Vector3d(1, 2, 3) + 0.1 * f * p;
          data.insert(data.end(), {float(d.x()), float(d.y()), float(d.z())});
        }
  return HeartMotion(g, frames, 0.8, std::move(data));
}

std::string parse_error(const std::string& bytes) {
  try {
    HeartMotion::parse(bytes, "m.motion");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(HeartMotion, RoundTripIsExact) {
  const HeartMotion m = small_motion();
  const HeartMotion back = HeartMotion::parse(m.serialize(), "mem");
  EXPECT_EQ(back.frames(), 4);
  EXPECT_DOUBLE_EQ(back.cycle_s(), 0.8);
  EXPECT_EQ(back.grid().dims, m.grid().dims);
  EXPECT_EQ(back.grid().origin_m, m.grid().origin_m);
  EXPECT_EQ(back.grid().spacing_m, m.grid().spacing_m);
  for (int f = 0; f < 4; ++f)
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) EXPECT_EQ(back.node_displacement_m(f, i, j, k), m.node_displacement_m(f, i, j, k));
  const auto path = std::filesystem::temp_directory_path() / "pcisim_heart_motion_test.motion";
  m.write(path.string());
  const HeartMotion file = HeartMotion::read(path.string());
  std::filesystem::remove(path);
  const Vector3d p(0.003, -0.011, 0.002);
  for (double phase : {0.0, 0.13, 0.5, 0.77}) EXPECT_EQ(file.displacement_m(p, phase), m.displacement_m(p, phase));
}

TEST(HeartMotion, TrilinearInSpaceThroughFramesInTime) {
  const HeartMotion m = small_motion();
  // frame f sits at phase f / 4; a field linear in position is reproduced exactly inside the grid
  const Vector3d p(0.004, 0.013, 0.0021);
  for (int f = 0; f < 4; ++f) {
    const Vector3d want = 0.001 * (f + 1) * Vector3d(1, 2, 3) + 0.1 * f * p;
    EXPECT_LT((m.displacement_m(p, f / 4.0) - want).norm(), 1e-9) << f;
  }
  // outside the grid the nearest boundary value holds
  EXPECT_LT((m.displacement_m(Vector3d(1, 1, 1), 0.25) - m.displacement_m(Vector3d(0.01, 0.02, 0.005), 0.25)).norm(),
            1e-12);
  // non-finite input: zero, never NaN
  EXPECT_EQ(m.displacement_m(Vector3d(NAN, 0, 0), 0.1), Vector3d::Zero());
  EXPECT_EQ(m.displacement_m(p, INFINITY), Vector3d::Zero());
}

TEST(HeartMotion, PeriodicAndContinuousAcrossTheCycle) {
  const HeartMotion m = make_synthetic_heart_motion();
  const Vector3d p = anatomy::heart_to_patient() * Vector3d(0.03, 0.02, 0.0);
  for (double phase : {0.0, 0.1, 0.35, 0.6, 0.95}) {
    EXPECT_LT((m.displacement_m(p, phase) - m.displacement_m(p, phase + 1.0)).norm(), 1e-12);
    EXPECT_LT((m.displacement_m(p, phase) - m.displacement_m(p, phase - 3.0)).norm(), 1e-12);
  }
  // continuous and smooth across the end of the cycle: a small phase step moves it little
  const double eps = 1e-4;
  EXPECT_LT((m.displacement_m(p, 1.0 - eps) - m.displacement_m(p, eps)).norm(), 1e-6);
  double max_jump = 0;
  for (int i = 0; i < 1000; ++i)
    max_jump = std::max(max_jump, (m.displacement_m(p, (i + 1) / 1000.0) - m.displacement_m(p, i / 1000.0)).norm());
  EXPECT_LT(max_jump, 1e-4);  // < 0.1 mm per 1/1000 cycle
}

// frames x dims x 12 bytes wrapped size_t to 764, so a 764-byte data part passed the size check
// (SEGV); found by fuzzing the scene's motion_file
TEST(HeartMotion, SizesThatOverflowAreRefused) {
  std::string good = small_motion().serialize();
  std::string header = good.substr(0, good.find("data float32-le\n") + 16);
  header.replace(header.find("frames 4"), 8, "frames 59809");
  header.replace(header.find("dims 3 3 2"), 10, "dims 24151 45005 23647");
  const std::string m = parse_error(header + std::string(764, '\0'));
  EXPECT_EQ(m.rfind("m.motion: data: expected ", 0), 0u) << m;
  EXPECT_NE(m.find("got 764"), std::string::npos) << m;
}

TEST(HeartMotion, BadFilesNameWhatIsWrong) {
  const std::string good = small_motion().serialize();
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  EXPECT_EQ(parse_error("hello\n"), "m.motion: magic line must be 'pcisim-heart-motion 1'");
  EXPECT_EQ(parse_error(replace("frames 4", "frames x")), "m.motion: field 'frames' needs 1 finite numbers, got 'x'");
  EXPECT_EQ(parse_error(replace("frames 4", "frames 1")), "m.motion: field 'frames' must be an integer >= 2");
  EXPECT_EQ(parse_error(replace("cycle_s 0.8", "cycle_s -1")), "m.motion: field 'cycle_s' must be > 0");
  EXPECT_EQ(parse_error(replace("cycle_s 0.8", "period 0.8")),
            "m.motion: expected field 'cycle_s' (line 3), got 'period 0.8'");
  EXPECT_NE(parse_error(replace("origin_m ", "origin_m 1 2 #")).find("field 'origin_m' needs 3 finite numbers"),
            std::string::npos);
  EXPECT_EQ(parse_error(replace("spacing_m 0.01", "spacing_m 0")),
            "m.motion: field 'spacing_m' must be > 0 on every axis");
  EXPECT_EQ(parse_error(replace("dims 3 3 2", "dims 3 3 1")), "m.motion: field 'dims' must be integers >= 2");
  EXPECT_EQ(parse_error(replace("dims 3 3 2", "dims 3 3 2 7")), "m.motion: field 'dims' has extra text '7'");
  EXPECT_EQ(parse_error(replace("data float32-le", "data float64")),
            "m.motion: field 'data' must say float32-le, got 'float64'");
  EXPECT_EQ(parse_error(good.substr(0, good.size() - 4)),
            "m.motion: data: expected 864 bytes (frames * dims * 3 float32), got 860");
  std::string nan = good;
  const float q = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan.data() + nan.size() - 4 * 3 * 18 * 2, &q, 4);  // frame 2, node 0
  EXPECT_EQ(parse_error(nan), "m.motion: data: non-finite displacement at frame 2, node 0");
  EXPECT_EQ(parse_error(good.substr(0, good.find("dims"))), "m.motion: header ends before field 'dims'");
  try {
    HeartMotion::read("/nonexistent.motion");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent.motion: cannot open");
  }
}

// LV cavity volume (m^3) with the cavity's vertices moved by the sequence at phase
double lv_volume_m3(const HeartMotion& m, double phase) {
  const anatomy::HeartMesh& mesh = anatomy::template_heart_mesh();
  double v = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_markers[f] != anatomy::kLvEndocardium) continue;
    Vector3d x[3];
    for (int k = 0; k < 3; ++k) {
      const Vector3d r = mesh.vertices_m.col(mesh.faces[f][k]);
      x[k] = r + m.displacement_m(r, phase);
    }
    v -= x[0].dot(x[1].cross(x[2])) / 6.0;  // the faces point into the cavity
  }
  return v;
}

TEST(HeartSyntheticMotion, EjectionFractionAndSystole) {
  const HeartMotion m = make_synthetic_heart_motion();
  const double ed = lv_volume_m3(m, 0.0);
  EXPECT_GT(ed, 70e-6);
  // the smallest volume (end-systole) comes ~35 % into the cycle
  double es = ed, es_phase = 0;
  for (int i = 0; i < 200; ++i) {
    const double v = lv_volume_m3(m, i / 200.0);
    if (v < es) es = v, es_phase = i / 200.0;
  }
  EXPECT_NEAR(es_phase, 0.35, 0.03);
  const double ef = 1.0 - es / ed;
  EXPECT_GT(ef, 0.55);
  EXPECT_LT(ef, 0.65);
  // and the cavity is back to its end-diastolic volume in diastole (filling done by 60 %)
  EXPECT_NEAR(lv_volume_m3(m, 0.7) / ed, 1.0, 0.01);
  EXPECT_NEAR(lv_volume_m3(m, 1.0) / ed, 1.0, 1e-9);
}

TEST(HeartSyntheticMotion, WallThickensBaseDescendsApexTwists) {
  const HeartMotion m = make_synthetic_heart_motion();
  const Eigen::Matrix3d h = anatomy::heart_to_patient();
  const anatomy::CavityEllipsoid lv = anatomy::lv_cavity();
  const double es = 0.35;
  // mid-ventricle, lateral LV wall (away from the RV): endocardium at the cavity, epicardium at 50 mm
  const Vector3d axis_point_mm(lv.centre_mm.x(), lv.centre_mm.y(), lv.centre_mm.z());
  const Vector3d out = Vector3d(std::cos(lv.azimuth_rad), std::sin(lv.azimuth_rad), 0);
  const Vector3d endo_mm = axis_point_mm + lv.semi_axes_mm.x() * out;
  const Vector3d epi_mm = axis_point_mm + 39.0 * out;
  ASSERT_GT(epi_mm.norm(), 48.5);  // just under the 50 mm epicardium
  ASSERT_LT(epi_mm.norm(), 50.0);
  auto inward_mm = [&](const Vector3d& x_mm) {
    const Vector3d d = h.transpose() * m.displacement_m(h * x_mm * 1e-3, es) * 1e3;
    return -d.dot(out);
  };
  const double endo_in = inward_mm(endo_mm), epi_in = inward_mm(epi_mm);
  EXPECT_GT(endo_in, 5.0);
  EXPECT_GT(epi_in, 0.3);
  EXPECT_GT(endo_in, 2.0 * epi_in);  // the wall thickens
  // the base descends toward the apex by 10-15 % of the long axis; the apex stays
  auto axial_mm = [&](const Vector3d& x_mm) {
    return (h.transpose() * m.displacement_m(h * x_mm * 1e-3, es)).z() * 1e3;
  };
  const Vector3d base_mm(0, 0, 28), apex_mm(0, 0, -49);
  const double shortening = (axial_mm(apex_mm) - axial_mm(base_mm)) / (base_mm.z() - apex_mm.z());
  EXPECT_GT(shortening, 0.10);
  EXPECT_LT(shortening, 0.15);
  EXPECT_LT(std::abs(axial_mm(apex_mm)), 1.0);
  // twist: base and apex turn opposite ways about the LV axis, a few degrees
  auto turn_deg = [&](const Vector3d& x_mm) {
    const Vector3d d = h.transpose() * m.displacement_m(h * x_mm * 1e-3, es) * 1e3;
    const Vector3d r = x_mm - axis_point_mm;
    const Vector3d tangent = Vector3d::UnitZ().cross(Vector3d(r.x(), r.y(), 0)).normalized();
    return d.dot(tangent) / Vector3d(r.x(), r.y(), 0).norm() * 180 / std::numbers::pi;
  };
  const double base_turn = turn_deg(axis_point_mm + Vector3d(0, 0, 30) + 35 * out);
  const double apex_turn = turn_deg(axis_point_mm + Vector3d(0, 0, -30) + 20 * out);
  EXPECT_LT(base_turn * apex_turn, 0.0);
  EXPECT_LT(std::abs(base_turn), 10.0);
  EXPECT_GT(std::abs(base_turn - apex_turn), 3.0);
}

TEST(HeartSyntheticMotion, EpicardialDisplacementIsAFewMillimetres) {
  const HeartMotion m = make_synthetic_heart_motion();
  const anatomy::HeartMesh& mesh = anatomy::template_heart_mesh();
  const Eigen::Matrix3d h = anatomy::heart_to_patient();
  double largest = 0, smallest = 1;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_markers[f] != anatomy::kEpicardium) continue;
    for (int v : mesh.faces[f]) {
      const Vector3d r = mesh.vertices_m.col(v);
      if ((h.transpose() * r).z() > 0.030) continue;  // the ventricles' epicardium
      const double d = m.displacement_m(r, 0.35).norm();
      largest = std::max(largest, d);
      smallest = std::min(smallest, d);
    }
  }
  EXPECT_GT(largest, 6e-3);
  EXPECT_LT(largest, 13e-3);
  EXPECT_LT(smallest, 3e-3);  // near the apex
}

}  // namespace
}  // namespace pcisim::anatomy
