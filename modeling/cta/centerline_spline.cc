#include "modeling/cta/centerline_spline.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace pcisim::modeling {
namespace {

std::vector<double> arc_lengths(const std::vector<Eigen::Vector3d>& p) {
  std::vector<double> s(p.size(), 0.0);
  for (size_t n = 1; n < p.size(); ++n) s[n] = s[n - 1] + (p[n] - p[n - 1]).norm();
  return s;
}

// the four non-zero cubic B-spline basis values at u in [0, m] (uniform knots, clamped ends):
// de Boor's recursion on the knot vector {0,0,0,0,1,...,m-1,m,m,m,m}; returns the first index
int basis(double u, int m, const std::vector<double>& knots, double out[4]) {
  int span = std::clamp(static_cast<int>(std::floor(u)), 0, m - 1) + 3;  // knots[span] <= u < knots[span+1]
  double left[4], right[4];
  out[0] = 1.0;
  for (int j = 1; j <= 3; ++j) {
    left[j] = u - knots[span + 1 - j];
    right[j] = knots[span + j] - u;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      const double den = right[r + 1] + left[j - r];
      const double t = den > 0 ? out[r] / den : 0.0;
      out[r] = saved + right[r + 1] * t;
      saved = left[j - r] * t;
    }
    out[j] = saved;
  }
  return span - 3;
}

}  // namespace

std::vector<Eigen::Vector3d> fit_and_sample(const std::vector<Eigen::Vector3d>& pts, const SplineOptions& o) {
  if (pts.size() < 2) return pts;
  const std::vector<double> s = arc_lengths(pts);
  const double total = s.back();
  if (total <= 1e-9) return {pts.front()};
  // m spans of knot_spacing (at least 1), m + 3 control points
  const int m = std::max(1, static_cast<int>(std::round(total / o.knot_spacing_mm)));
  const int nc = m + 3;
  std::vector<double> knots(m + 7);
  for (int i = 0; i < m + 7; ++i) knots[i] = std::clamp(i - 3, 0, m);
  Eigen::MatrixXd ata = Eigen::MatrixXd::Zero(nc, nc);
  Eigen::MatrixXd atb = Eigen::MatrixXd::Zero(nc, 3);
  for (size_t n = 0; n < pts.size(); ++n) {
    double b[4];
    const int first = basis(s[n] / total * m, m, knots, b);
    const double w = (n == 0 || n + 1 == pts.size()) ? 1e4 : 1.0;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) ata(first + r, first + c) += w * b[r] * b[c];
      atb.row(first + r) += w * b[r] * pts[n].transpose();
    }
  }
  // second differences of the control points, scaled to the number of data points per span
  const double lambda = o.smoothing * double(pts.size()) / double(m);
  for (int i = 0; i + 2 < nc; ++i) {
    const int idx[3] = {i, i + 1, i + 2};
    const double c[3] = {1.0, -2.0, 1.0};
    for (int r = 0; r < 3; ++r) {
      for (int q = 0; q < 3; ++q) ata(idx[r], idx[q]) += lambda * c[r] * c[q];
    }
  }
  const Eigen::MatrixXd ctrl = ata.ldlt().solve(atb);
  // sample densely, then every sample_spacing of the curve's own arc length
  const int dense = std::max(8, static_cast<int>(total / 0.05));
  std::vector<Eigen::Vector3d> curve(dense + 1);
  for (int i = 0; i <= dense; ++i) {
    double b[4];
    const int first = basis(double(i) / dense * m, m, knots, b);
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int r = 0; r < 4; ++r) p += b[r] * ctrl.row(first + r).transpose();
    curve[i] = p;
  }
  const std::vector<double> cs = arc_lengths(curve);
  const int count = std::max(1, static_cast<int>(std::round(cs.back() / o.sample_spacing_mm)));
  std::vector<Eigen::Vector3d> out;
  size_t seg = 0;
  for (int i = 0; i <= count; ++i) {
    const double t = cs.back() * i / count;
    while (seg + 2 < curve.size() && cs[seg + 1] < t) ++seg;
    const double len = cs[seg + 1] - cs[seg];
    const double f = len > 0 ? std::clamp((t - cs[seg]) / len, 0.0, 1.0) : 0.0;
    out.push_back(curve[seg] + f * (curve[seg + 1] - curve[seg]));
  }
  return out;
}

std::vector<double> carry_along(const std::vector<Eigen::Vector3d>& pts, const std::vector<double>& v,
                                const std::vector<Eigen::Vector3d>& samples) {
  const std::vector<double> s = arc_lengths(pts), t = arc_lengths(samples);
  std::vector<double> out(samples.size(), v.empty() ? 0.0 : v.front());
  if (pts.size() < 2) return out;
  size_t seg = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const double u = t.back() > 0 ? t[i] / t.back() * s.back() : 0.0;
    while (seg + 2 < pts.size() && s[seg + 1] < u) ++seg;
    const double len = s[seg + 1] - s[seg];
    const double f = len > 0 ? std::clamp((u - s[seg]) / len, 0.0, 1.0) : 0.0;
    out[i] = v[seg] + f * (v[seg + 1] - v[seg]);
  }
  return out;
}

}  // namespace pcisim::modeling
