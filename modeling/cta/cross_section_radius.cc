#include "modeling/cta/cross_section_radius.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <numbers>
#include "realtime/percentile.h"

namespace pcisim::modeling {
namespace {

// separable Gaussian of sigma pixels on an n x n image
void gaussian2d(const std::vector<float>& in, std::vector<float>* out, std::vector<float>* tmp, int n, double sigma) {
  const int r = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
  std::vector<float> w(2 * r + 1);
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += w[i + r] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)));
  for (float& x : w) x = static_cast<float>(x / sum);
  tmp->assign(in.size(), 0.0f);
  out->assign(in.size(), 0.0f);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      double acc = 0;
      for (int i = -r; i <= r; ++i) acc += w[i + r] * in[y * n + std::clamp(x + i, 0, n - 1)];
      (*tmp)[y * n + x] = static_cast<float>(acc);
    }
  }
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      double acc = 0;
      for (int i = -r; i <= r; ++i) acc += w[i + r] * (*tmp)[std::clamp(y + i, 0, n - 1) * n + x];
      (*out)[y * n + x] = static_cast<float>(acc);
    }
  }
}

float bilinear(const std::vector<float>& f, int n, double x, double y) {
  x = std::clamp(x, 0.0, n - 1.0001);
  y = std::clamp(y, 0.0, n - 1.0001);
  const int i = static_cast<int>(x), j = static_cast<int>(y);
  const double fx = x - i, fy = y - j;
  const float* p = f.data() + j * n + i;
  return static_cast<float>((1 - fy) * ((1 - fx) * p[0] + fx * p[1]) + fy * ((1 - fx) * p[n] + fx * p[n + 1]));
}

}  // namespace

double cross_section_radius(const FloatImage& hu, const Eigen::Vector3d& centre, const Eigen::Vector3d& tangent,
                            double guess_mm, const RadiusOptions& o, RadiusWorkspace* ws) {
  guess_mm = std::max(guess_mm, 0.2);
  const double h = std::clamp(guess_mm / o.pixels_per_radius, 0.05, 0.2);
  const double half_mm = o.field_radii * guess_mm + 0.6;
  const int c = static_cast<int>(std::ceil(half_mm / h));
  const int n = 2 * c + 1;
  // the section's axes
  const Eigen::Vector3d t = tangent.normalized();
  const Eigen::Vector3d a = (std::abs(t.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY());
  const Eigen::Vector3d u = t.cross(a).normalized(), w = t.cross(u);
  // resample the plane (continuous indices of the crop grid)
  const Eigen::Matrix3d to_index = hu.grid.direction.inverse();
  const Eigen::Vector3d inv = hu.grid.spacing_mm.cwiseInverse();
  const Eigen::Vector3d c0 = (to_index * (centre - hu.grid.origin_mm)).cwiseProduct(inv);
  const Eigen::Vector3d du = (to_index * u).cwiseProduct(inv) * h, dw = (to_index * w).cwiseProduct(inv) * h;
  ws->image.resize(size_t(n) * n);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      ws->image[y * n + x] = hu.at(c0 + (x - c) * du + (y - c) * dw, -1000.0f);
    }
  }
  gaussian2d(ws->image, &ws->smooth, &ws->next, n, std::max(0.5, o.presmooth_mm / h));
  // edge function g [heart eq 2] and its gradient
  ws->g.assign(size_t(n) * n, 1.0f);
  ws->gx.assign(size_t(n) * n, 0.0f);
  ws->gy.assign(size_t(n) * n, 0.0f);
  float gmax = 1e-6f;
  std::vector<float>& grad = ws->next;
  grad.assign(size_t(n) * n, 0.0f);
  for (int y = 1; y + 1 < n; ++y) {
    for (int x = 1; x + 1 < n; ++x) {
      const float ix = 0.5f * (ws->smooth[y * n + x + 1] - ws->smooth[y * n + x - 1]);
      const float iy = 0.5f * (ws->smooth[(y + 1) * n + x] - ws->smooth[(y - 1) * n + x]);
      grad[y * n + x] = std::sqrt(ix * ix + iy * iy);
      gmax = std::max(gmax, grad[y * n + x]);
    }
  }
  for (size_t i = 0; i < grad.size(); ++i) {
    ws->g[i] = static_cast<float>(1.0 / (1.0 + std::pow(grad[i] / gmax / o.edge_k, o.edge_power)));
  }
  for (int y = 1; y + 1 < n; ++y) {
    for (int x = 1; x + 1 < n; ++x) {
      ws->gx[y * n + x] = 0.5f * (ws->g[y * n + x + 1] - ws->g[y * n + x - 1]);
      ws->gy[y * n + x] = 0.5f * (ws->g[(y + 1) * n + x] - ws->g[(y - 1) * n + x]);
    }
  }
  // Phi: a circle of a third of the guess (at least 1.5 pixels) around the centre
  const double r0 = std::max(1.5, guess_mm / 3 / h);
  ws->phi.resize(size_t(n) * n);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) ws->phi[y * n + x] = static_cast<float>(std::hypot(x - c, y - c) - r0);
  }
  ws->next = ws->phi;
  // two phases: the balloon carries the contour out to where g stops it, then with v = 0 the
  // attraction term alone settles it on the valley of g (the steepest edge), from either side
  const double dt = 0.3;
  for (int phase = 0; phase < 2; ++phase) {
    const double v = phase == 0 ? o.balloon_v : 0.0;
    double last_area = -1;
    for (int it = 0; it < o.iterations / 2; ++it) {
      double area = 0;
      for (int y = 1; y + 1 < n; ++y) {
        for (int x = 1; x + 1 < n; ++x) {
          const float* p = ws->phi.data() + y * n + x;
          const double dxm = p[0] - p[-1], dxp = p[1] - p[0], dym = p[0] - p[-n], dyp = p[n] - p[0];
          // outward balloon: Osher-Sethian upwind for a positive speed
          const double grad_plus = std::sqrt(std::pow(std::max(dxm, 0.0), 2) + std::pow(std::min(dxp, 0.0), 2) +
                                             std::pow(std::max(dym, 0.0), 2) + std::pow(std::min(dyp, 0.0), 2));
          // curvature (central differences)
          const double px = 0.5 * (p[1] - p[-1]), py = 0.5 * (p[n] - p[-n]);
          const double pxx = p[1] - 2 * p[0] + p[-1], pyy = p[n] - 2 * p[0] + p[-n];
          const double pxy = 0.25 * (p[n + 1] - p[n - 1] - p[-n + 1] + p[-n - 1]);
          const double m2 = px * px + py * py;
          const double kappa =
              m2 > 1e-12 ? (pxx * py * py - 2 * px * py * pxy + pyy * px * px) / std::pow(m2, 1.5) : 0.0;
          const double gv = ws->g[y * n + x];
          // attraction to the edge: velocity -grad g, upwind
          const double vx = -ws->gx[y * n + x], vy = -ws->gy[y * n + x];
          const double adv = vx * (vx > 0 ? dxm : dxp) + vy * (vy > 0 ? dym : dyp);
          const double phi_t = -gv * v * grad_plus + gv * o.curvature_eps * kappa * std::sqrt(m2) - o.attraction * adv;
          ws->next[y * n + x] = static_cast<float>(p[0] + dt * phi_t);
          if (ws->next[y * n + x] < 0) area += 1;
        }
      }
      std::swap(ws->phi, ws->next);
      if (it % 10 == 9) {
        if (last_area >= 0 && std::abs(area - last_area) < 0.5) break;
        last_area = area;
      }
    }
  }
  // the median distance to the zero level along rays from the centre
  std::vector<double> r(o.rays);
  for (int k = 0; k < o.rays; ++k) {
    const double ang = 2 * std::numbers::pi * k / o.rays, cx = std::cos(ang), cy = std::sin(ang);
    double prev = bilinear(ws->phi, n, c, c), s = 0.0, hit = c;
    for (s = 0.25; s <= c; s += 0.25) {
      const double v = bilinear(ws->phi, n, c + s * cx, c + s * cy);
      if (prev < 0 && v >= 0) {
        hit = s - 0.25 + 0.25 * (-prev) / (v - prev);
        break;
      }
      prev = v;
    }
    r[k] = std::min<double>(s > c ? c : hit, c);
  }
  return realtime::upper_median_in_place(std::span<double>(r)) * h;
}

}  // namespace pcisim::modeling
