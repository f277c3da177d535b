// capstan (wire_force_rigs.h): a wire of negligible bending stiffness drawn round a bent tube and
// held at its far end, the hub pulling it back: pull = hold e^(mu theta) (Euler's capstan
// equation: along a wire wrapped on a surface, dT/ds = mu T kappa, so T grows by e^(mu theta),
// theta the tangent's turn). Beyond 180 degrees the bend is a helix of radius a (the wire's, on
// the tube's inner side) rising c per radian: its tangent turns by theta a / sqrt(a^2 + c^2).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "anatomy/phantom/tube_phantoms.h"
#include "bench/wire_force_rigs.h"
#include "physics/guidewire/rod_wire.h"
#include "physics/guidewire/tube_lumen.h"
#include "realtime/clock.h"

namespace pcisim::bench::wire_force {
namespace {

constexpr double kLumenRadiusM = 1.5e-3, kBendRadiusM = 15e-3;
constexpr double kEntryM = 30e-3, kExitM = 40e-3, kHelixRisePerTurnM = 5e-3;
// drawn through at kDrawSpeed by kLeaderN on the tip until the tip is kPastBendM beyond the bend;
// then held while the hub pulls back at kPullSpeed for kPullS, the pull averaged over the last half
constexpr double kLeaderN = 0.01, kDrawSpeedMPerS = 0.03, kPastBendM = 25e-3;
constexpr double kPullSpeedMPerS = 0.01, kPullS = 1.5;

// the tube's centerline, sampled every 0.5 mm: straight from the exit, then the bend turning
// towards +x about an axis along y (rising along y beyond 180 degrees), then straight along its
// tangent. The entry straight runs along the helix's start, as the wire on its inner side
// (radius wire_radius_m) leaves it: a wire pulled round a kink there would wrap it too (3.4
// degrees at 5 mm a turn, +1.2 % on the capstan at mu 0.2)
struct CapstanTube {
  std::vector<Eigen::Vector3d> points, tangents;
  double bend_end_arc_m = 0.0;  // arc length where the bend ends
  Eigen::Vector3d entry_tangent = Eigen::Vector3d::UnitZ(), exit_tangent = Eigen::Vector3d::UnitX();
};

CapstanTube capstan_tube(double angle_rad, double wire_radius_m) {
  CapstanTube t;
  const double rise_per_rad = angle_rad > std::numbers::pi ? kHelixRisePerTurnM / (2.0 * std::numbers::pi) : 0.0;
  const double ds = 0.5e-3;
  auto add = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& d) {
    t.points.push_back(p);
    t.tangents.push_back(d.normalized());
  };
  t.entry_tangent = Eigen::Vector3d(0.0, rise_per_rad, wire_radius_m).normalized();
  // from a little behind the exit, so the catheter's exit is inside the lumen
  for (double z = -2e-3; z < kEntryM; z += ds) add(z * t.entry_tangent, t.entry_tangent);
  const Eigen::Vector3d centre = kEntryM * t.entry_tangent + Eigen::Vector3d(kBendRadiusM, 0.0, 0.0);
  const int bend_samples = static_cast<int>(std::ceil(angle_rad * kBendRadiusM / ds));
  for (int k = 0; k <= bend_samples; ++k) {
    const double a = angle_rad * k / bend_samples;
    add(centre + Eigen::Vector3d(-kBendRadiusM * std::cos(a), rise_per_rad * a, kBendRadiusM * std::sin(a)),
        Eigen::Vector3d(kBendRadiusM * std::sin(a), rise_per_rad, kBendRadiusM * std::cos(a)));
  }
  t.bend_end_arc_m = kEntryM + 2e-3 + angle_rad * std::hypot(kBendRadiusM, rise_per_rad);
  t.exit_tangent = t.tangents.back();
  const Eigen::Vector3d end = t.points.back();
  for (double s = ds; s <= kExitM + 1e-9; s += ds) add(end + s * t.exit_tangent, t.exit_tangent);
  return t;
}

// the centerline's tangent at the point nearest p, and that point's arc length
std::pair<Eigen::Vector3d, double> nearest_tangent(const CapstanTube& t, const Eigen::Vector3d& p) {
  size_t best = 0;
  for (size_t i = 1; i < t.points.size(); ++i)
    if ((t.points[i] - p).squaredNorm() < (t.points[best] - p).squaredNorm()) best = i;
  double arc = 0.0;
  for (size_t i = 1; i <= best; ++i) arc += (t.points[i] - t.points[i - 1]).norm();
  return {t.tangents[best], arc};
}

}  // namespace

CapstanResult run_capstan(const Capstan& c) {
  const double angle_rad = c.angle_deg * std::numbers::pi / 180.0;
  const physics::VesselContactParams contact;
  // the wire's helix: on the bend's inner side, at the wall margin
  const double inner_m = kLumenRadiusM - contact.wall_margin_m;
  const CapstanTube tube = capstan_tube(angle_rad, kBendRadiusM - inner_m);
  const anatomy::VesselTree tree = anatomy::tube_through(tube.points, kLumenRadiusM);
  const physics::TubeLumen lumen(tree);
  physics::FrictionParams mu;
  mu.body_static = mu.tip_static = mu.body_kinetic = mu.tip_kinetic = c.mu;
  physics::GuidewireParams g;
  g.model = physics::GuidewireModel::kRod;
  g.rod_contact = contact_scheme();
  g.segment_count = 300;
  g.tip_length_m = 0.0;
  g.tip_angle_deg = 0.0;
  g.bending_stiffness_nm2 = g.tip_bending_stiffness_nm2 = 1e-9;
  g.torsional_rigidity_nm2 = 1e-9;
  // the catheter's exit on the bend's inner side of the entry straight, at the wall margin: the
  // taut wire runs along that side into the bend, so the bend's whole angle is wrapped
  const Eigen::Vector3d exit_m(inner_m, 0, 0);
  physics::RodWire w(g, physics::CatheterPath({exit_m - 0.2 * tube.entry_tangent, exit_m}), &lumen, contact, mu);
  const int tip = w.node_count() - 1;
  CapstanResult r;
  const double a = kBendRadiusM - inner_m,
               rise = angle_rad > std::numbers::pi ? kHelixRisePerTurnM / (2 * std::numbers::pi) : 0.0;
  r.wrap_rad = angle_rad * a / std::hypot(a, rise);
  r.capstan_n = c.hold_n * std::exp(c.mu * r.wrap_rad);
  // drawn through by its tip, the hub feeding behind it
  double fed_m = 0.0;
  const double most_m = 0.9 * g.length_m;
  for (int k = 0; k < 100000 && fed_m < most_m; ++k) {
    const auto [ahead, arc_m] = nearest_tangent(tube, w.nodes_m()[tip]);
    if (arc_m >= tube.bend_end_arc_m + kPastBendM) {
      r.drawn_through = true;
      break;
    }
    w.set_node_force_n(tip, kLeaderN * ahead);
    fed_m += kDrawSpeedMPerS * kStepS;
    w.step(fed_m, 0.0, kStepS);
    if (!w.rod().all_finite()) return r;
  }
  if (!r.drawn_through) return r;
  // held at the tip, pulled back at the hub
  w.set_node_force_n(tip, c.hold_n * tube.exit_tangent);
  std::vector<double> step_ms, pulls, step_end_pulls;
  std::vector<int> substeps;
  const int steps = static_cast<int>(std::lround(kPullS / kStepS));
  for (int k = 1; k <= steps; ++k) {
    const int64_t start = realtime::monotonic_ns();
    w.step(fed_m - kPullSpeedMPerS * k * kStepS, 0.0, kStepS);
    step_ms.push_back((realtime::monotonic_ns() - start) * 1e-6);
    substeps.push_back(w.contact_report().substeps);
    r.residual_mm = std::max(r.residual_mm, 1e3 * w.contact_report().residual_m);
    // the wire pulls the hub distally: against insertion, so the push-back is negative
    if (k > steps / 2) {
      pulls.push_back(-w.mean_hub_axial_force_n());
      step_end_pulls.push_back(-w.hub_axial_force_n());
    }
  }
  double sum = 0.0;
  for (double p : pulls) sum += p;
  r.pull_n = sum / static_cast<double>(pulls.size());
  for (double p : pulls) r.pull_spread_n = std::max(r.pull_spread_n, std::abs(p - r.pull_n));
  for (double p : step_end_pulls) r.pull_step_end_n += p / static_cast<double>(step_end_pulls.size());
  r.cost = step_cost(step_ms, substeps);
  return r;
}

std::string json_line(const Capstan& c, const CapstanResult& r) {
  return fmt::format(
      "{{\"case\": \"capstan\", \"mu\": {}, \"angle_deg\": {}, \"hold_n\": {}, \"drawn_through\": {}, "
      "\"pull_n\": {:.6g}, \"pull_spread_n\": {:.3g}, \"pull_step_end_n\": {:.6g}, \"wrap_rad\": {:.6g}, "
      "\"capstan_n\": {:.6g}, \"error_pct\": "
      "{:.3f}, \"residual_mm\": {:.3g}, {}}}",
      c.mu, c.angle_deg, c.hold_n, r.drawn_through, r.pull_n, r.pull_spread_n, r.pull_step_end_n, r.wrap_rad,
      r.capstan_n, 100.0 * (r.pull_n / r.capstan_n - 1.0), r.residual_mm, cost_json(r.cost));
}

}  // namespace pcisim::bench::wire_force
