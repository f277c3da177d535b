// dead_end (wire_force_rigs.h): the default wire fed into the closed end of the rod tests' bent
// tube. What a cardiologist feels pushing into an occlusion: the hub's force rising with feed
// until the grip slips (feed_refuse_force_n), the wire's own length kept (nothing crumples), the
// tip pressing the end, nothing through the wall.
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

// fed kApproachM over 3.5 s, then on towards kCommandM over kPushS, then held kHoldS
constexpr double kApproachM = 0.11, kCommandM = 0.2, kPushS = 3.0, kHoldS = 1.0;

}  // namespace

DeadEndResult run_dead_end() {
  const anatomy::VesselTree tree = anatomy::bent_tube_phantom();
  const physics::TubeLumen lumen(tree);
  const physics::VesselContactParams contact;
  physics::FrictionParams mu;
  mu.body_static = mu.tip_static = 0.3;
  mu.body_kinetic = mu.tip_kinetic = 0.2;
  physics::GuidewireParams g;
  g.model = physics::GuidewireModel::kRod;
  g.rod_contact = contact_scheme();
  g.segment_count = 300;
  g.tip_angle_deg = 0.0;
  physics::RodWire w(g, physics::CatheterPath({Eigen::Vector3d(0, 0, -0.2), Eigen::Vector3d(0, 0, 0)}), &lumen, contact,
                     mu);
  for (double t = 0.0; t < 3.5; t += kStepS) w.step(kApproachM * std::min(t / 3.0, 1.0), 0.0, kStepS);
  DeadEndResult r;
  std::vector<double> step_ms;
  std::vector<int> substeps;
  const int steps = static_cast<int>(std::lround((kPushS + kHoldS) / kStepS));
  double last_hub_n = w.hub_axial_force_n();
  for (int k = 1; k <= steps; ++k) {
    const double t = k * kStepS;
    const double command_m = kApproachM + (kCommandM - kApproachM) * std::min(t / kPushS, 1.0);
    const int64_t start = realtime::monotonic_ns();
    w.step(command_m, 0.0, kStepS);
    DeadEndSample s;
    s.step_ms = (realtime::monotonic_ns() - start) * 1e-6;
    s.commanded_mm = 1e3 * command_m;
    s.fed_mm = 1e3 * w.fed_length_m();
    s.hub_n = w.hub_axial_force_n();
    s.tip_n = w.tip_contact_force_n();
    s.crumpled_mm = 1e3 * w.compression_m();  // how much shorter the free wire is than what was fed
    s.substeps = w.contact_report().substeps;
    s.worst_mm = -1e9;
    for (int i = w.first_free_node(); i < w.node_count(); ++i)
      s.worst_mm = std::max(s.worst_mm, 1e3 * (lumen.sample(w.nodes_m()[i]).distance_m + contact.wall_margin_m));
    r.samples.push_back(s);
    step_ms.push_back(s.step_ms);
    substeps.push_back(s.substeps);
    r.max_hub_n = std::max(r.max_hub_n, s.hub_n);
    r.max_tip_n = std::max(r.max_tip_n, s.tip_n);
    r.max_crumpled_mm = std::max(r.max_crumpled_mm, s.crumpled_mm);
    r.worst_mm = std::max(r.worst_mm, s.worst_mm);
    r.largest_hub_jump_n = std::max(r.largest_hub_jump_n, std::abs(s.hub_n - last_hub_n));
    last_hub_n = s.hub_n;
    if (!w.rod().all_finite()) break;
  }
  r.refused_mm = 1e3 * w.refused_feed_m();
  r.cost = step_cost(step_ms, substeps);
  return r;
}

std::string json_line(const DeadEndResult& r) {
  std::string curve;
  for (size_t i = 0; i < r.samples.size(); ++i) {
    const DeadEndSample& s = r.samples[i];
    curve += fmt::format("{}[{:.2f}, {:.2f}, {:.4f}, {:.4f}, {:.3f}, {:.4f}, {}, {:.1f}]", i ? ", " : "",
                         s.commanded_mm, s.fed_mm, s.hub_n, s.tip_n, s.crumpled_mm, s.worst_mm, s.substeps, s.step_ms);
  }
  return fmt::format(
      "{{\"case\": \"dead_end\", \"max_hub_n\": {:.4f}, \"largest_hub_jump_n\": {:.4f}, \"max_tip_n\": {:.4f}, "
      "\"max_crumpled_mm\": {:.3f}, \"worst_mm\": {:.4f}, \"refused_mm\": {:.2f}, {}, \"curve_columns\": "
      "[\"commanded_mm\", "
      "\"fed_mm\", \"hub_n\", \"tip_n\", \"crumpled_mm\", \"worst_mm\", \"substeps\", \"step_ms\"], \"curve\": [{}]}}",
      r.max_hub_n, r.largest_hub_jump_n, r.max_tip_n, r.max_crumpled_mm, r.worst_mm, r.refused_mm, cost_json(r.cost),
      curve);
}

}  // namespace pcisim::bench::wire_force
