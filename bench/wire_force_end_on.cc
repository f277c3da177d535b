// end_on (wire_force_rigs.h): a straight wire pushed into the closed end of a straight tube. Held
// by the catheter at one end (clamped) and by the tube's end at the other (pinned: the end's cap
// keeps the tip on the axis), it first buckles at the clamped-pinned Euler load
// P = x1^2 EI / L^2, x1 = 4.4934 the first root of tan x = x (Timoshenko & Gere, Theory of
// Elastic Stability, 2.6: the effective length 0.699 L). Afterwards the tube's wall holds it.
// The buckling is found by load, not by a rigid push: a straight column answers a push by its
// axial stiffness alone (EA / L, 2e5 N/m at 30 mm), so a push of 5 mm/s overshoots Euler's load
// several times within one substep in any solver, before the column can bow.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "anatomy/phantom/tube_phantoms.h"
#include "bench/wire_force_rigs.h"
#include "physics/guidewire/rod_wire.h"
#include "physics/guidewire/tube_lumen.h"
#include "realtime/clock.h"

namespace pcisim::bench::wire_force {
namespace {

// the first root of tan x = x, by Newton from 4.5
double clamped_pinned_root() {
  double x = 4.5;
  for (int i = 0; i < 50; ++i) x -= (std::tan(x) - x) / (1.0 / (std::cos(x) * std::cos(x)) - 1.0);
  return x;
}

// fed to 1 mm short of the end at kApproachSpeed, on to the end at kPushSpeed, loaded until it
// buckles (below), then kMoreM further at kPushSpeed; the lateral gravity is the imperfection (its
// own sag at 50 mm is 0.1 um)
constexpr double kApproachSpeedMPerS = 0.05, kPushSpeedMPerS = 0.005, kMoreM = 20e-3;
constexpr double kLateralGravityMPerS2 = 0.05;
// the load: raised by this fraction of EI / L^2 a step (Euler's load is 20.2 EI / L^2: about 0.1 %
// of it a step), at most kMaxLoadSteps; the feed moves kLoadGain of the column's axial compliance
// times the shortfall, at most kMaxLoadFeedM a step
constexpr double kLoadRateFraction = 0.02;
constexpr int kMaxLoadSteps = 3000;
constexpr double kLoadGain = 0.5, kMaxLoadFeedM = 0.05e-3;
// the run stops as blown up beyond this hub force (about 400 times the Euler load at 50 mm)
constexpr double kBlownUpN = 50.0;

}  // namespace

EndOnResult run_end_on(const EndOn& c) {
  const physics::VesselContactParams contact;
  const double length_m = c.length_mm * 1e-3, clearance_m = c.clearance_mm * 1e-3;
  const double lumen_radius_m = clearance_m + contact.wall_margin_m;
  // the tube's centerline ends where its cap's pole, less the margin, is length_mm from the exit
  const double end_z_m = length_m - clearance_m;
  std::vector<Eigen::Vector3d> centerline;
  for (double z = -2e-3; z < end_z_m; z += 0.5e-3) centerline.push_back({0.0, 0.0, z});
  centerline.push_back({0.0, 0.0, end_z_m});
  const anatomy::VesselTree tree = anatomy::tube_through(centerline, lumen_radius_m);
  const physics::TubeLumen lumen(tree);
  physics::GuidewireParams g;
  g.model = physics::GuidewireModel::kRod;
  g.rod_contact = contact_scheme();
  g.segment_count = 300;
  g.tip_length_m = 0.0;
  g.tip_angle_deg = 0.0;
  g.feed_refuse_force_n = 100.0;  // the grip holds: the wire is pushed on whatever it takes
  physics::RodWire w(g, physics::CatheterPath({Eigen::Vector3d(0, 0, -0.2), Eigen::Vector3d(0, 0, 0)}), &lumen,
                     contact);
  w.set_gravity_m_per_s2(Eigen::Vector3d(kLateralGravityMPerS2, 0.0, 0.0));
  EndOnResult r;
  const double ei = g.bending_stiffness_nm2, x1 = clamped_pinned_root();
  r.euler_n = x1 * x1 * ei / (length_m * length_m);  // the column's own length replaces L once it buckles
  double fed_m = 0.0;
  while (fed_m < length_m - 1e-3) {
    fed_m = std::min(fed_m + kApproachSpeedMPerS * kStepS, length_m - 1e-3);
    w.step(fed_m, 0.0, kStepS);
  }
  std::vector<double> step_ms;
  std::vector<int> substeps;
  bool loading = false;  // the buckle counts only while loaded
  // one step, timed; false where the wire blew up (the run stops)
  auto step = [&]() {
    const int64_t start = realtime::monotonic_ns();
    w.step(fed_m, 0.0, kStepS);
    step_ms.push_back((realtime::monotonic_ns() - start) * 1e-6);
    substeps.push_back(w.contact_report().substeps);
    // a recovery (the rod went non-finite and was laid out afresh) is a blow-up too
    if (!w.rod().all_finite() || w.recoveries() > 0) {
      r.blew_up_at_mm = 1e3 * (fed_m - length_m);
      return false;
    }
    double lateral_m = 0.0;
    for (int i = w.first_free_node(); i < w.node_count(); ++i) {
      const Eigen::Vector3d& p = w.nodes_m()[i];
      lateral_m = std::max(lateral_m, std::hypot(p.x(), p.y()));
      r.worst_mm = std::max(r.worst_mm, 1e3 * (lumen.sample(p).distance_m + contact.wall_margin_m));
    }
    const double hub_n = w.hub_axial_force_n();
    r.max_hub_n = std::max(r.max_hub_n, hub_n);
    r.max_crumpled_mm = std::max(r.max_crumpled_mm, 1e3 * w.compression_m());
    // blown up: a force no wire of this section carries, or the tip thrown out of the tube's end
    if (std::abs(hub_n) > kBlownUpN || w.nodes_m().back().z() < 0.5 * length_m) {
      r.blew_up_at_mm = 1e3 * (fed_m - length_m);
      return false;
    }
    if (loading && !r.buckled && lateral_m >= 0.5 * clearance_m) {
      r.buckled = true;
      r.buckling_n = hub_n;
      // the column: from the hub node (the rod's clamp: a node, so up to a segment behind the
      // exit once the feed passes a whole segment) to the end's stop
      const double column_m = length_m - w.nodes_m()[w.first_free_node() - 1].z();
      r.column_mm = 1e3 * column_m;
      r.euler_n = x1 * x1 * ei / (column_m * column_m);
    }
    return true;
  };
  // up to the end at the push's speed; then, by load: the hub's force raised by
  // kLoadRateFraction EI / L^2 a step, the feed moved by what the column's axial compliance gives
  // for the shortfall (a straight column answers a rigid push by its axial stiffness EA / L
  // alone: 1 um of feed is 0.06-0.2 N at 100-30 mm, Euler's load or more, before it can bow),
  // until it buckles (a buckle is counted only here)
  bool alive = true;
  while (alive && fed_m < length_m && !(w.wall_force_n().back() > 0.0)) {
    fed_m = std::min(fed_m + kPushSpeedMPerS * kStepS, length_m);
    alive = step();
  }
  loading = true;
  const double axial_compliance_m_per_n = length_m / physics::kWireAxialStiffnessN;
  double target_n = std::max(w.hub_axial_force_n(), 0.0);
  const double load_rate_n = kLoadRateFraction * ei / (length_m * length_m);
  for (int j = 0; alive && !r.buckled && j < kMaxLoadSteps; ++j) {
    target_n += load_rate_n;
    const double shortfall_n = target_n - w.hub_axial_force_n();
    fed_m += std::clamp(kLoadGain * axial_compliance_m_per_n * shortfall_n, -kMaxLoadFeedM, kMaxLoadFeedM);
    alive = step();
  }
  loading = false;
  // then kMoreM further by the rigid push
  const double more_from_m = fed_m;
  while (alive && fed_m < more_from_m + kMoreM) {
    fed_m += kPushSpeedMPerS * kStepS;
    alive = step();
  }
  r.cost = step_cost(step_ms, substeps);
  return r;
}

std::string json_line(const EndOn& c, const EndOnResult& r) {
  return fmt::format(
      "{{\"case\": \"end_on\", \"length_mm\": {}, \"clearance_mm\": {}, \"buckled\": {}, \"column_mm\": {:.3f}, "
      "\"buckling_n\": {:.6g}, "
      "\"euler_n\": {:.6g}, \"error_pct\": {:.3f}, \"max_hub_n\": {:.6g}, \"max_crumpled_mm\": {:.3f}, "
      "\"blew_up_at_mm\": {:.2f}, \"worst_mm\": {:.4f}, {}}}",
      c.length_mm, c.clearance_mm, r.buckled, r.column_mm, r.buckling_n, r.euler_n,
      100.0 * (r.buckling_n / r.euler_n - 1.0), r.max_hub_n, r.max_crumpled_mm, r.blew_up_at_mm, r.worst_mm,
      cost_json(r.cost));
}

}  // namespace pcisim::bench::wire_force
