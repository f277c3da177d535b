// tip_on_wall (wire_force_rigs.h): a wire (a uniform section) fed L out of a straight catheter,
// its tip pushed sideways D by a rigid frictionless finger (its face the plane x = -D, its lower
// edge kept 0.4 mm behind the tip so only the tip meets it). The finger's force against the
// cantilever under a dead tip load perpendicular to its clamp: 3 EI D / L^3 for small D, the
// exact elastica (physics/rod/elastica.h, inverted for the load that deflects the tip by D) up to
// D = 0.3 L.
#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "bench/wire_force_rigs.h"
#include "physics/guidewire/rod_wire.h"
#include "physics/rod/elastica.h"
#include "realtime/clock.h"

namespace pcisim::bench::wire_force {
namespace {

// the finger comes in over kRampS and holds until kHoldEndS; its edge sits this far behind the
// tip (the node before it is at least 0.85 segments behind at D = 0.3 L, 1 mm segments)
constexpr double kRampS = 3.0, kHoldEndS = 5.0, kEdgeBehindTipM = 0.4e-3;

// the finger: the lumen is x < face_x_m wherever z is beyond edge_z_m, and unbounded elsewhere
struct Finger final : physics::LumenQuery {
  double face_x_m = 1.0, edge_z_m = 0.0;
  physics::WallSample sample(const Eigen::Vector3d& p) const override {
    if (p.z() < edge_z_m) return {-1.0, Eigen::Vector3d::UnitX()};
    return {p.x() - face_x_m, Eigen::Vector3d::UnitX()};
  }
};

// the dead tip load that deflects a clamped elastica's tip by dv_over_l (bisection on alpha)
double elastica_load_parameter(double dv_over_l) {
  double lo = 0.0, hi = 1.0;
  while (physics::rod::cantilever_tip_load(hi).dv_over_l < dv_over_l && hi < 1e3) hi *= 2.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (physics::rod::cantilever_tip_load(mid).dv_over_l < dv_over_l ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

TipOnWallResult run_tip_on_wall(const TipOnWall& c) {
  const double length_m = c.length_mm * 1e-3, d_m = c.deflection_mm * 1e-3;
  physics::GuidewireParams g;
  g.model = physics::GuidewireModel::kRod;
  g.rod_contact = contact_scheme();
  g.segment_count = c.segments;
  g.rod_substeps = c.substeps;
  g.tip_length_m = 0.0;
  g.tip_angle_deg = 0.0;
  const physics::VesselContactParams contact;
  Finger finger;
  physics::RodWire w(g, physics::CatheterPath({Eigen::Vector3d(0, 0, -0.2), Eigen::Vector3d(0, 0, 0)}), &finger,
                     contact);
  for (double t = 0.0; t < 1.0; t += kStepS) w.step(length_m * std::min(t / 0.5, 1.0), 0.0, kStepS);
  // the finger comes in until the tip's centre sits D aside, then holds; the force is the mean
  // over the last half second
  std::vector<double> step_ms;
  std::vector<int> substeps;
  double force_sum = 0;
  int force_n = 0;
  const int steps = static_cast<int>(kHoldEndS / kStepS);
  for (int k = 0; k < steps; ++k) {
    const double t = k * kStepS;
    finger.face_x_m = contact.wall_margin_m - d_m * std::min(t / kRampS, 1.0);
    finger.edge_z_m = w.nodes_m().back().z() - kEdgeBehindTipM;
    const int64_t a = realtime::monotonic_ns();
    w.step(length_m, 0.0, kStepS);
    step_ms.push_back((realtime::monotonic_ns() - a) * 1e-6);
    substeps.push_back(w.contact_report().substeps);
    if (t >= kHoldEndS - 0.5) {
      double f = 0;
      for (int i = w.first_free_node(); i < w.node_count(); ++i) f += w.wall_force_n()[i];
      force_sum += f;
      ++force_n;
    }
  }
  TipOnWallResult r;
  // the references for the wire's own free length: whole segments from the hub node to the tip
  const double free_m = (w.node_count() - w.first_free_node()) * w.rod().segment_length_m();
  r.free_length_mm = 1e3 * free_m;
  r.contact_force_n = force_sum / std::max(force_n, 1);
  r.ei_nm2 = g.bending_stiffness_nm2;
  r.beam_n = 3.0 * r.ei_nm2 * d_m / (free_m * free_m * free_m);
  r.elastica_n = elastica_load_parameter(d_m / free_m) * r.ei_nm2 / (free_m * free_m);
  r.tip_x_mm = 1e3 * w.nodes_m().back().x();
  r.residual_mm = 1e3 * w.contact_report().residual_m;
  r.contacts = w.contact_report().contacts;
  r.cost = step_cost(step_ms, substeps);
  return r;
}

std::string json_line(const TipOnWall& c, const TipOnWallResult& r) {
  return fmt::format(
      "{{\"case\": \"tip_on_wall\", \"length_mm\": {}, \"free_length_mm\": {:.4g}, \"deflection_mm\": {}, "
      "\"segments\": {}, \"substeps\": {}, "
      "\"contact_force_n\": {:.6g}, \"ei_nm2\": {:.6g}, \"beam_n\": {:.6g}, \"elastica_n\": {:.6g}, "
      "\"error_pct\": {:.4f}, \"tip_x_mm\": {:.4f}, \"residual_mm\": {:.3g}, \"contacts\": {}, {}}}",
      c.length_mm, r.free_length_mm, c.deflection_mm, c.segments, c.substeps, r.contact_force_n, r.ei_nm2, r.beam_n,
      r.elastica_n, 100.0 * (r.contact_force_n / r.elastica_n - 1.0), r.tip_x_mm, r.residual_mm, r.contacts,
      cost_json(r.cost));
}

}  // namespace pcisim::bench::wire_force
