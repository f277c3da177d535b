#include "physics/rod/elastica.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace pcisim::physics::rod {
namespace {

constexpr double kPi = std::numbers::pi;

// theta'' as a function of the arc length s in [0, 1] and the angle
enum class Load { kTipPerpendicular, kSelfWeight, kTipAxial };

double curvature_rate(Load load, double p, double s, double theta) {
  switch (load) {
    case Load::kTipPerpendicular:
      return -p * std::cos(theta);
    case Load::kSelfWeight:
      return -p * (1.0 - s) * std::cos(theta);
    case Load::kTipAxial:
      return -p * std::sin(theta);
  }
  return 0.0;
}

struct State {
  double theta, kappa, x, y;  // angle, theta' = curvature, integrals of cos and sin from the tip
};

State derivative(Load load, double p, double s, const State& u) {
  return {u.kappa, curvature_rate(load, p, s, u.theta), std::cos(u.theta), std::sin(u.theta)};
}

State axpy(const State& u, double h, const State& k) {
  return {u.theta + h * k.theta, u.kappa + h * k.kappa, u.x + h * k.x, u.y + h * k.y};
}

struct Shot {
  State clamp;        // the state reached at s = 0
  bool crossed_zero;  // theta reached 0 before the clamp (too small a tip angle for branch 1)
};

// RK4 from the free tip (s = 1, theta' = 0, theta = tip angle) back to the clamp (s = 0)
Shot shoot(Load load, double p, double tip_angle, int steps) {
  const double h = -1.0 / steps;
  State u{tip_angle, 0.0, 0.0, 0.0};
  for (int i = 0; i < steps; ++i) {
    const double s = 1.0 + i * h;
    const State k1 = derivative(load, p, s, u);
    const State k2 = derivative(load, p, s + 0.5 * h, axpy(u, 0.5 * h, k1));
    const State k3 = derivative(load, p, s + 0.5 * h, axpy(u, 0.5 * h, k2));
    const State k4 = derivative(load, p, s + h, axpy(u, h, k3));
    u.theta += h / 6.0 * (k1.theta + 2.0 * k2.theta + 2.0 * k3.theta + k4.theta);
    u.kappa += h / 6.0 * (k1.kappa + 2.0 * k2.kappa + 2.0 * k3.kappa + k4.kappa);
    u.x += h / 6.0 * (k1.x + 2.0 * k2.x + 2.0 * k3.x + k4.x);
    u.y += h / 6.0 * (k1.y + 2.0 * k2.y + 2.0 * k3.y + k4.y);
    if (u.theta < 0.0 && i + 1 < steps) return {u, true};
  }
  return {u, false};
}

// bisection on the tip angle in [0, upper] until theta(0) = 0 on the first branch (theta
// monotone from the clamp to the tip); theta(0) rises with the tip angle there
ElasticaTip solve(Load load, double p, double upper, int steps) {
  if (!(steps >= 16)) throw std::invalid_argument("elastica: steps must be >= 16");
  double lo = 0.0, hi = upper;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * upper; ++it) {
    const double mid = 0.5 * (lo + hi);
    const Shot shot = shoot(load, p, mid, steps);
    if (shot.crossed_zero || shot.clamp.theta < 0.0) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  const double tip = 0.5 * (lo + hi);
  const Shot shot = shoot(load, p, tip, steps);
  // x, y were integrated from s = 1 down to 0: the integrals over [0, 1] are their negatives
  return {-shot.clamp.y, 1.0 + shot.clamp.x, tip};
}

void check_load(double p, const char* what) {
  if (!std::isfinite(p) || p < 0.0) throw std::invalid_argument(std::string("elastica: ") + what + " must be >= 0");
}

}  // namespace

ElasticaTip cantilever_tip_load(double alpha, const ElasticaOptions& options) {
  check_load(alpha, "alpha");
  if (alpha == 0.0) return {};
  return solve(Load::kTipPerpendicular, alpha, 0.5 * kPi, options.steps);
}

ElasticaTip cantilever_self_weight(double w, const ElasticaOptions& options) {
  check_load(w, "w");
  if (w == 0.0) return {};
  return solve(Load::kSelfWeight, w, 0.5 * kPi, options.steps);
}

ElasticaTip column_post_buckling(double load_ratio, const ElasticaOptions& options) {
  check_load(load_ratio, "load ratio");
  if (load_ratio <= 1.0) return {};
  return solve(Load::kTipAxial, 0.25 * kPi * kPi * load_ratio, kPi, options.steps);
}

double elliptic_k(double k) {
  if (!(k >= 0.0 && k < 1.0)) throw std::invalid_argument("elliptic_k: modulus must be in [0, 1)");
  double a = 1.0, b = std::sqrt(1.0 - k * k);
  for (int it = 0; it < 64 && std::abs(a - b) > 1e-15 * a; ++it) {
    const double an = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = an;
  }
  return 0.5 * kPi / a;
}

// E(k) = K(k) (1 - sum_n 2^(n-1) c_n^2) over the AGM sequence with c_0 = k (Abramowitz & Stegun 17.6)
double elliptic_e(double k) {
  if (!(k >= 0.0 && k < 1.0)) throw std::invalid_argument("elliptic_e: modulus must be in [0, 1)");
  double a = 1.0, b = std::sqrt(1.0 - k * k), c = k;
  double sum = 0.5 * c * c, weight = 0.5;
  for (int it = 0; it < 64 && std::abs(c) > 1e-15 * a; ++it) {
    const double an = 0.5 * (a + b);
    c = 0.5 * (a - b);
    b = std::sqrt(a * b);
    a = an;
    weight *= 2.0;
    sum += weight * c * c;
  }
  return 0.5 * kPi / a * (1.0 - sum);
}

ElasticaTip column_post_buckling_elliptic(double load_ratio) {
  check_load(load_ratio, "load ratio");
  if (load_ratio <= 1.0) return {};
  const double target = 0.5 * kPi * std::sqrt(load_ratio);  // K(k) = sqrt(P L^2 / EI)
  double lo = 0.0, hi = 1.0;
  for (int it = 0; it < 200 && hi - lo > 1e-16; ++it) {
    const double mid = 0.5 * (lo + hi);
    (elliptic_k(mid) < target ? lo : hi) = mid;
  }
  const double k = 0.5 * (lo + hi);
  const double kk = elliptic_k(k), ee = elliptic_e(k);
  return {2.0 * k / kk, 2.0 - 2.0 * ee / kk, 2.0 * std::asin(k)};
}

double euler_load_n(double bending_stiffness_nm2, double length_m) {
  return kPi * kPi * bending_stiffness_nm2 / (4.0 * length_m * length_m);
}

double catenary_sag_m(double span_m, double chain_length_m) {
  if (!(span_m > 0.0) || !(chain_length_m > span_m) || !std::isfinite(chain_length_m)) {
    throw std::invalid_argument("catenary: need 0 < span < chain length");
  }
  // with u = span / (2 c): sinh(u) / u = chain_length / span, increasing in u
  const double ratio = chain_length_m / span_m;
  double lo = 0.0, hi = 700.0;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (std::sinh(mid) / mid < ratio ? lo : hi) = mid;
  }
  const double u = 0.5 * (lo + hi);
  const double c = 0.5 * span_m / u;
  return c * (std::cosh(u) - 1.0);
}

}  // namespace pcisim::physics::rod
