// Frangi's vesselness (modeling/image/vesselness.h) against what its equations give in closed form:
// the eigenvalues of known matrices, and the response of shapes whose Hessians are known (a
// Gaussian line, a Gaussian sheet, a Gaussian blob).
#include "modeling/image/vesselness.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include <Eigen/Geometry>

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

TEST(Vesselness, EigenvaluesOfKnownMatrices) {
  // diagonal: the entries, ordered by magnitude
  auto l = symmetric_eigenvalues_by_magnitude(-3, 1, 2, 0, 0, 0);
  EXPECT_DOUBLE_EQ(l[0], 1);
  EXPECT_DOUBLE_EQ(l[1], 2);
  EXPECT_DOUBLE_EQ(l[2], -3);
  // [[2, 1, 0], [1, 2, 0], [0, 0, -5]]: 1, 3, -5
  l = symmetric_eigenvalues_by_magnitude(2, 2, -5, 1, 0, 0);
  EXPECT_NEAR(l[0], 1, 1e-12);
  EXPECT_NEAR(l[1], 3, 1e-12);
  EXPECT_NEAR(l[2], -5, 1e-12);
  // a rotation of diag(-1, -4, 0.5) about z by 30 deg and x by 50 deg keeps its eigenvalues
  const Eigen::Matrix3d r =
      (Eigen::AngleAxisd(0.52, Vector3d::UnitZ()) * Eigen::AngleAxisd(0.87, Vector3d::UnitX())).toRotationMatrix();
  const Eigen::Matrix3d a = r * Vector3d(-1, -4, 0.5).asDiagonal() * r.transpose();
  l = symmetric_eigenvalues_by_magnitude(a(0, 0), a(1, 1), a(2, 2), a(0, 1), a(0, 2), a(1, 2));
  EXPECT_NEAR(l[0], 0.5, 1e-9);
  EXPECT_NEAR(l[1], -1, 1e-9);
  EXPECT_NEAR(l[2], -4, 1e-9);
  // a repeated eigenvalue (the axis of a round tube), rotated off the axes: -2, -2, 0 (the acos
  // of the closed form is ill-conditioned at a double root: ~1e-8, far below the measure's needs)
  const Eigen::Matrix3d t = r * Vector3d(-2, -2, 0).asDiagonal() * r.transpose();
  l = symmetric_eigenvalues_by_magnitude(t(0, 0), t(1, 1), t(2, 2), t(0, 1), t(0, 2), t(1, 2));
  EXPECT_NEAR(l[0], 0, 1e-6);
  EXPECT_NEAR(l[1], -2, 1e-6);
  EXPECT_NEAR(l[2], -2, 1e-6);
}

// a 0.25 mm grid of 32 mm along each axis, valued 400 exp(-d^2 / 2 w^2) by a distance d (mm) from
// the centre's line, plane or point
FloatImage shape(const std::function<double(const Vector3d&)>& d_mm, double w_mm) {
  ImageGrid g;
  g.dims = {128, 128, 128};
  g.spacing_mm = Vector3d::Constant(0.25);
  FloatImage im{g, std::vector<float>(g.size())};
  for (int64_t n = 0; n < g.size(); ++n) {
    const auto [i, j, k] = g.ijk(n);
    const Vector3d p = g.physical_mm(Vector3d(double(i), double(j), double(k))) - Vector3d::Constant(16);
    const double d = d_mm(p);
    im.v[n] = static_cast<float>(400 * std::exp(-d * d / (2 * w_mm * w_mm)));
  }
  return im;
}

double at_centre(const FloatImage& v) {
  return v.v[v.grid.index(64, 64, 64)];
}

TEST(Vesselness, ALineIsATubeAndASheetAndABlobAreNot) {
  VesselnessOptions o;
  o.sigma_min_mm = 0.4;
  o.sigma_max_mm = 1.0;
  o.sigma_steps = 3;
  o.gamma = 20;  // the shapes' structure (~100 HU) far above it: the S term is ~1
  o.threads = 2;
  const double w = 0.7;
  // a line along a diagonal (the Hessian's cross terms count), a sheet, a blob
  const Vector3d axis = Vector3d(1, 1, 0.5).normalized();
  const FloatImage line = shape([&](const Vector3d& p) { return (p - p.dot(axis) * axis).norm(); }, w);
  const FloatImage sheet = shape([&](const Vector3d& p) { return std::abs(p.dot(axis)); }, w);
  const FloatImage blob = shape([&](const Vector3d& p) { return p.norm(); }, w);
  const double v_line = at_centre(bright_tube_vesselness(line, nullptr, o));
  const double v_sheet = at_centre(bright_tube_vesselness(sheet, nullptr, o));
  const double v_blob = at_centre(bright_tube_vesselness(blob, nullptr, o));
  std::printf("vesselness at the centre: line %.3f, sheet %.3f, blob %.3f\n", v_line, v_sheet, v_blob);
  // the line: l1 = 0, l2 = l3, so Ra = 1, Rb = 0, and S far above gamma: V = 1 - exp(-2) = 0.865
  EXPECT_NEAR(v_line, 1 - std::exp(-2.0), 0.02);
  // the sheet: one eigenvalue only (l2 = 0): not bright in two directions
  EXPECT_LT(v_sheet, 0.01);
  // the blob: l1 = l2 = l3, Rb = 1: V = (1 - exp(-2)) exp(-2) = 0.117
  EXPECT_NEAR(v_blob, (1 - std::exp(-2.0)) * std::exp(-2.0), 0.02);
}

// the scale-normalised response of a Gaussian line of width w, smoothed by sigma, is largest at
// sigma = w (the cross-section's second derivative is -A sigma^2 w^2 / (w^2 + sigma^2)^2); with
// gamma near that response, the measure peaks at the scale of the tube
TEST(Vesselness, ThinLinesAnswerAtTheirOwnScale) {
  VesselnessOptions o;
  o.threads = 2;
  o.gamma = 40;
  auto response = [&](double w, double sigma) {
    o.sigma_min_mm = o.sigma_max_mm = sigma;
    o.sigma_steps = 1;
    return at_centre(bright_tube_vesselness(
        shape([](const Vector3d& p) { return Vector3d(p.x(), p.y(), 0).norm(); }, w), nullptr, o));
  };
  for (double w : {0.5, 1.0}) {
    const double below = response(w, 0.6 * w), at = response(w, w), above = response(w, 1.6 * w);
    std::printf("line of width %.1f mm: V %.3f at sigma %.2f, %.3f at %.2f, %.3f at %.2f\n", w, below, 0.6 * w, at, w,
                above, 1.6 * w);
    EXPECT_GT(at, below);
    EXPECT_GT(at, above);
  }
}

// only the voxels asked for are computed; the rest are 0
TEST(Vesselness, OnlyTheVoxelsAskedFor) {
  const FloatImage line = shape([](const Vector3d& p) { return Vector3d(p.x(), p.y(), 0).norm(); }, 0.7);
  Mask where = Mask::zeros(line.grid);
  where.v[line.grid.index(64, 64, 40)] = 1;
  VesselnessOptions o;
  o.threads = 2;
  const FloatImage v = bright_tube_vesselness(line, &where, o);
  EXPECT_GT(v.v[line.grid.index(64, 64, 40)], 0.5);
  EXPECT_EQ(v.v[line.grid.index(64, 64, 64)], 0.0f);
}

}  // namespace
}  // namespace pcisim::modeling
