// torque_lag (wire_force_rigs.h): the hub turned a whole turn at a constant rate, the tip's
// rotation about its own axis against time. In a straight frictionless tube the tip follows the
// hub (the twist a turn puts in the free wire is GJ-stiff and nothing holds it back): the baseline
// that checks the measure. In a tortuous tube friction holds the wire where it presses the bends,
// the free wire winds up and the tip lags, then catches up at once when the wound-up torque beats
// the tip's friction (whip: the tip turns faster than the hub).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "anatomy/phantom/tube_phantoms.h"
#include "bench/wire_force_rigs.h"
#include "physics/guidewire/rod_wire.h"
#include "physics/guidewire/tube_lumen.h"
#include "realtime/clock.h"

namespace pcisim::bench::wire_force {
namespace {

constexpr double kLumenRadiusM = 1.5e-3, kDs = 0.5e-3;
// fed to kFedM at kFeedSpeed, then the hub turns kTurnDeg at kTurnRateDegPerS, then is held kHoldS
constexpr double kFeedSpeedMPerS = 0.03, kTurnDeg = 360.0, kTurnRateDegPerS = 180.0, kHoldS = 2.0;

// a centerline drawn like a turtle: straights and circular bends, sampled every kDs
class Turtle {
 public:
  Turtle() { points_.push_back(p_); }
  void straight(double length_m) {
    const int n = static_cast<int>(std::ceil(length_m / kDs));
    const Eigen::Vector3d from = p_;
    for (int k = 1; k <= n; ++k) points_.push_back(from + (length_m * k / n) * t_);
    p_ = points_.back();
  }
  // a bend by angle_deg at radius_m towards `towards` (its part across the tangent)
  void bend(double angle_deg, double radius_m, const Eigen::Vector3d& towards) {
    const Eigen::Vector3d u = (towards - towards.dot(t_) * t_).normalized();
    const Eigen::Vector3d centre = p_ + radius_m * u, t0 = t_;
    const double angle = angle_deg * std::numbers::pi / 180.0;
    const int n = static_cast<int>(std::ceil(angle * radius_m / kDs));
    for (int k = 1; k <= n; ++k) {
      const double a = angle * k / n;
      points_.push_back(centre - radius_m * std::cos(a) * u + radius_m * std::sin(a) * t0);
    }
    p_ = points_.back();
    t_ = std::cos(angle) * t0 + std::sin(angle) * u;
  }
  const std::vector<Eigen::Vector3d>& points() const { return points_; }

 private:
  Eigen::Vector3d p_{0.0, 0.0, -2e-3}, t_ = Eigen::Vector3d::UnitZ();
  std::vector<Eigen::Vector3d> points_;
};

// the tortuous tube: three bends in three planes (90, 90 and 120 degrees at 10-12 mm radius, the
// sizes of a coronary's first bends; the last bend ends 115.5 mm along the centerline from the
// catheter's exit), 147.5 mm of centerline in all; or a straight tube of 140 mm
std::vector<Eigen::Vector3d> torque_lag_centerline(bool tortuous) {
  Turtle t;
  if (!tortuous) {
    t.straight(142e-3);  // from 2 mm behind the exit
    return t.points();
  }
  t.straight(32e-3);
  t.bend(90, 10e-3, Eigen::Vector3d::UnitX());
  t.straight(15e-3);
  t.bend(90, 12e-3, Eigen::Vector3d::UnitY());
  t.straight(15e-3);
  t.bend(120, 10e-3, Eigen::Vector3d::UnitZ());  // the first bend turned +z to +x, the second +x to +y
  t.straight(30e-3);
  return t.points();
}

// the rotation (rad) that takes the tip's material frame of the last step to this step's about
// the tip's tangent, the tangent's own turn taken out (the old frame transported to the new
// tangent by the smallest rotation)
double tip_spin_rad(const Eigen::Quaterniond& before, const Eigen::Quaterniond& now) {
  const Eigen::Vector3d t0 = before * Eigen::Vector3d::UnitZ(), t1 = now * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d d1_moved = Eigen::Quaterniond::FromTwoVectors(t0, t1) * (before * Eigen::Vector3d::UnitX());
  const Eigen::Vector3d d1 = now * Eigen::Vector3d::UnitX();
  return std::atan2(d1_moved.cross(d1).dot(t1), d1_moved.dot(d1));
}

}  // namespace

TorqueLagResult run_torque_lag(const TorqueLag& c) {
  const std::vector<Eigen::Vector3d> centerline = torque_lag_centerline(c.tortuous);
  const anatomy::VesselTree tree = anatomy::tube_through(centerline, kLumenRadiusM);
  const physics::TubeLumen lumen(tree);
  const physics::VesselContactParams contact;
  physics::FrictionParams mu;
  if (!c.friction) mu.body_static = mu.body_kinetic = mu.tip_static = mu.tip_kinetic = 0.0;
  physics::GuidewireParams g;
  g.model = physics::GuidewireModel::kRod;
  g.rod_contact = contact_scheme();
  g.segment_count = 300;
  g.tip_angle_deg = 0.0;  // a straight tip: its spin is the wire's, not the tip swinging round the lumen
  physics::RodWire w(g, physics::CatheterPath({Eigen::Vector3d(0, 0, -0.2), Eigen::Vector3d(0, 0, 0)}), &lumen, contact,
                     mu);
  TorqueLagResult r;
  // a step that went non-finite is recovered inside the wire (laid straight out of the catheter):
  // the run then measures nothing and is not completed
  const auto sound = [&] { return w.rod().all_finite() && w.recoveries() == 0; };
  double fed_m = 0.0;
  while (fed_m < c.fed_mm * 1e-3) {
    fed_m = std::min(fed_m + kFeedSpeedMPerS * kStepS, c.fed_mm * 1e-3);
    w.step(fed_m, 0.0, kStepS);
    if (!sound()) return r;
  }
  // settled, then turned and held
  for (int k = 0; k < 15; ++k) w.step(fed_m, 0.0, kStepS);
  const int turn_steps = static_cast<int>(std::lround(kTurnDeg / kTurnRateDegPerS / kStepS));
  const int hold_steps = static_cast<int>(std::lround(kHoldS / kStepS));
  std::vector<double> step_ms;
  std::vector<int> substeps;
  Eigen::Quaterniond tip_q = w.rod().orientations().back();
  double tip_rad = 0.0, previous_tip_deg = 0.0;
  for (int k = 1; k <= turn_steps + hold_steps; ++k) {
    const double hub_deg = kTurnDeg * std::min(1.0, static_cast<double>(k) / turn_steps);
    const int64_t start = realtime::monotonic_ns();
    w.step(fed_m, hub_deg * std::numbers::pi / 180.0, kStepS);
    step_ms.push_back((realtime::monotonic_ns() - start) * 1e-6);
    substeps.push_back(w.contact_report().substeps);
    if (!sound()) return r;
    const Eigen::Quaterniond q = w.rod().orientations().back();
    tip_rad += tip_spin_rad(tip_q, q);
    tip_q = q;
    const double tip_deg = tip_rad * 180.0 / std::numbers::pi;
    r.samples.push_back({k * kStepS, hub_deg, tip_deg});
    r.max_lag_deg = std::max(r.max_lag_deg, hub_deg - tip_deg);
    r.max_lead_deg = std::max(r.max_lead_deg, tip_deg - hub_deg);
    r.max_tip_rate_ratio = std::max(r.max_tip_rate_ratio, (tip_deg - previous_tip_deg) / kStepS / kTurnRateDegPerS);
    previous_tip_deg = tip_deg;
    if (k == turn_steps) r.lag_at_turn_end_deg = hub_deg - tip_deg;
    r.final_lag_deg = hub_deg - tip_deg;
  }
  r.completed = true;
  r.cost = step_cost(step_ms, substeps);
  return r;
}

std::string json_line(const TorqueLag& c, const TorqueLagResult& r) {
  std::string curve;
  for (size_t i = 0; i < r.samples.size(); ++i)
    curve += fmt::format("{}[{:.3f}, {:.2f}, {:.2f}]", i ? ", " : "", r.samples[i].t_s, r.samples[i].hub_deg,
                         r.samples[i].tip_deg);
  return fmt::format(
      "{{\"case\": \"torque_lag\", \"tortuous\": {}, \"friction\": {}, \"fed_mm\": {}, \"completed\": {}, "
      "\"lag_at_turn_end_deg\": {:.2f}, \"final_lag_deg\": {:.2f}, \"max_lag_deg\": {:.2f}, \"max_lead_deg\": {:.2f}, "
      "\"max_tip_rate_ratio\": {:.3f}, {}, \"curve_columns\": [\"t_s\", \"hub_deg\", \"tip_deg\"], \"curve\": [{}]}}",
      c.tortuous, c.friction, c.fed_mm, r.completed, r.lag_at_turn_end_deg, r.final_lag_deg, r.max_lag_deg,
      r.max_lead_deg, r.max_tip_rate_ratio, cost_json(r.cost), curve);
}

}  // namespace pcisim::bench::wire_force
