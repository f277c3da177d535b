#pragma once
// Exact planar elastica answers, the analytic reference the rod models are checked against
// (issue 15). An inextensible, unshearable rod of length L and bending stiffness EI, tangent
// angle theta(s): moment balance gives theta'' as a function of the load; each case below is a
// two-point boundary problem in the arc length s, solved by shooting: RK4 from the free tip (where theta' = 0 and the
// tip angle is the unknown) back to the clamp, and bisection on the tip angle until theta(0) = 0. Everything is
// nondimensional (s / L, loads as load parameters), so it holds in any units. Not on any hot path: no allocation, some
// tens of milliseconds per answer.

namespace pcisim::physics::rod {

struct ElasticaTip {
  double dv_over_l = 0.0;  // deflection of the tip perpendicular to the clamped direction / L
  double dh_over_l = 0.0;  // displacement of the tip along the clamped direction (shortening) / L
  double angle_rad = 0.0;  // tip angle relative to the clamped direction
};

struct ElasticaOptions {
  int steps = 4000;  // RK4 steps over the length (error ~ steps^-4; 4000 gives ~1e-12 at load 10)
};

// (a) cantilever clamped along +x, dead tip load P along -y, alpha = P L^2 / EI >= 0:
// theta'' = -alpha cos(theta), theta(0) = 0, theta'(1) = 0 (theta measured downwards)
ElasticaTip cantilever_tip_load(double alpha, const ElasticaOptions& options = {});

// (b) the same cantilever under its own weight q per length, w = q L^3 / EI >= 0:
// theta'' = -w (1 - s) cos(theta), theta(0) = 0, theta'(1) = 0
ElasticaTip cantilever_self_weight(double w, const ElasticaOptions& options = {});

// (c) clamped-free column under a dead axial compressive tip load P, ratio = P / P_cr with the
// Euler load P_cr = pi^2 EI / (4 L^2): theta'' = -(pi^2 / 4) ratio sin(theta). Below or at
// ratio 1 the straight column is the only equilibrium (all zero); above it the first buckled
// branch (tip angle in (0, pi)). dv is the lateral tip deflection.
ElasticaTip column_post_buckling(double load_ratio, const ElasticaOptions& options = {});

// (c') the same branch from its closed form in complete elliptic integrals (an independent
// answer, no ODE): with k = sin(tip_angle / 2), sqrt(P L^2 / EI) = K(k), dv / L = 2 k / K(k),
// 1 - dh / L = 2 E(k) / K(k) - 1 (Timoshenko & Gere, Theory of Elastic Stability, 1961, 2.7)
ElasticaTip column_post_buckling_elliptic(double load_ratio);

// Euler's critical load of a clamped-free column, P_cr = pi^2 EI / (4 L^2)
double euler_load_n(double bending_stiffness_nm2, double length_m);

// (d) catenary: an inextensible chain of length chain_length_m > span_m, no stiffness, hung
// between two points span_m apart at equal height: y = c cosh(x / c) with c from
// chain_length / 2 = c sinh(span / (2 c)) (bisection); returns the sag c (cosh(span / 2c) - 1)
double catenary_sag_m(double span_m, double chain_length_m);

// complete elliptic integrals of the first and second kind, modulus k in [0, 1) (AGM)
double elliptic_k(double k);
double elliptic_e(double k);

}  // namespace pcisim::physics::rod
