// pcisim-bench wire-force: the rod wire's forces against mechanics the bench does not compute
// itself (issue #33). The case built so far:
//   tip_on_wall: a wire (a uniform section) fed L out of a straight catheter, its tip pushed
//   sideways D by a rigid frictionless finger (its face the plane x = -D, its lower edge kept
//   0.5 mm behind the tip so only the tip meets it), with the wall inside the rod's solve
//   (RodContactScheme::kSolve). The finger's force against the cantilever under a dead tip load
//   perpendicular to its clamp: 3 EI D / L^3 for small D, the exact elastica (physics/rod/
//   elastica.h, inverted for the load that deflects the tip by D) up to D = 0.3 L.
// The capstan and end-on cases of the issue are not built: the solve scheme is not yet stable on
// a curved wall or once a wire buckles (docs/guidewire.md).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench/bench_registry.h"
#include "bench/bench_stats.h"
#include "bench/machine_info.h"
#include "physics/guidewire/rod_wire.h"
#include "physics/rod/elastica.h"
#include "realtime/clock.h"

namespace pcisim::bench {
namespace {

constexpr double kDt = 1.0 / 30.0;
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

// the wire's free length is whole segments (the hub is a node): 48 mm is whole at 0.5-4 mm
struct TipOnWall {
  double length_mm = 48, deflection_mm = 4.8;
  int segments = 300, substeps = 8;
};

struct TipOnWallResult {
  double free_length_mm = 0;  // what the wire has free: whole segments, the requested L rounded up
  double contact_force_n = 0, ei_nm2 = 0, beam_n = 0, elastica_n = 0, tip_x_mm = 0, residual_mm = 0;
  int contacts = 0;
  double step_ms_p50 = 0, step_ms_p99 = 0;
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

TipOnWallResult run_tip_on_wall(const TipOnWall& c) {
  const double length_m = c.length_mm * 1e-3, d_m = c.deflection_mm * 1e-3;
  physics::GuidewireParams g;
  g.model = physics::GuidewireModel::kRod;
  g.rod_contact = physics::RodContactScheme::kSolve;
  g.segment_count = c.segments;
  g.rod_substeps = c.substeps;
  g.tip_length_m = 0.0;
  g.tip_angle_deg = 0.0;
  const physics::VesselContactParams contact;
  Finger finger;
  physics::RodWire w(g, physics::CatheterPath({Eigen::Vector3d(0, 0, -0.2), Eigen::Vector3d(0, 0, 0)}), &finger,
                     contact);
  for (double t = 0.0; t < 1.0; t += kDt) w.step(length_m * std::min(t / 0.5, 1.0), 0.0, kDt);
  // the finger comes in until the tip's centre sits D aside, then holds; the force is the mean
  // over the last half second
  std::vector<double> step_ms;
  double force_sum = 0;
  int force_n = 0;
  const int steps = static_cast<int>(kHoldEndS / kDt);
  for (int k = 0; k < steps; ++k) {
    const double t = k * kDt;
    finger.face_x_m = contact.wall_margin_m - d_m * std::min(t / kRampS, 1.0);
    finger.edge_z_m = w.nodes_m().back().z() - kEdgeBehindTipM;
    const int64_t a = realtime::monotonic_ns();
    w.step(length_m, 0.0, kDt);
    step_ms.push_back((realtime::monotonic_ns() - a) * 1e-6);
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
  r.step_ms_p50 = percentile(step_ms, 0.5);
  r.step_ms_p99 = percentile(step_ms, 0.99);
  return r;
}

std::string json_line(const TipOnWall& c, const TipOnWallResult& r) {
  return fmt::format(
      "{{\"case\": \"tip_on_wall\", \"length_mm\": {}, \"free_length_mm\": {:.4g}, \"deflection_mm\": {}, "
      "\"segments\": {}, \"substeps\": {}, "
      "\"contact_force_n\": {:.6g}, \"ei_nm2\": {:.6g}, \"beam_n\": {:.6g}, \"elastica_n\": {:.6g}, "
      "\"error_pct\": {:.4f}, \"tip_x_mm\": {:.4f}, \"residual_mm\": {:.3g}, \"contacts\": {}, \"step_ms_p50\": "
      "{:.3f}, "
      "\"step_ms_p99\": {:.3f}}}",
      c.length_mm, r.free_length_mm, c.deflection_mm, c.segments, c.substeps, r.contact_force_n, r.ei_nm2, r.beam_n,
      r.elastica_n, 100.0 * (r.contact_force_n / r.elastica_n - 1.0), r.tip_x_mm, r.residual_mm, r.contacts,
      r.step_ms_p50, r.step_ms_p99);
}

constexpr const char* kUsage =
    "pcisim-bench wire-force --case tip_on_wall [--length-mm L (48)] [--deflection-mm D (4.8)] [--segments N (300)]\n"
    "                        [--substeps S (8)]\n"
    "  a wire of free length L (10-150 mm; whole segments of the 300 mm wire, else rounded up), its tip\n"
    "  pushed sideways D (0 < D <= 0.3 L) by a frictionless\n"
    "  finger, the wall inside the rod's solve; one JSON line: the finger's force (contact_force_n), the\n"
    "  wire's EI (ei_nm2), 3 EI D / L^3 (beam_n) and the elastica's load for that deflection (elastica_n)\n"
    "pcisim-bench wire-force [--out DIR (docs/benchmarks)]\n"
    "  the sweep: D / L 0.01-0.3 at L 48 mm, L 30 and 100 mm (held out) at D / L 0.2, and segments 75-600\n"
    "  at D / L 0.1; wire-force.md and .json\n"
    "  (the issue's capstan and end_on cases are not built yet: docs/guidewire.md says why)\n";

int run(const std::vector<std::string>& args) {
  std::string out_dir = PCISIM_SOURCE_DIR "/docs/benchmarks", kind;
  TipOnWall c;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--help") {
      std::printf("%s", kUsage);
      return 0;
    }
    if (i + 1 >= args.size()) {
      std::fprintf(stderr, "pcisim-bench wire-force: %s needs a value\n%s", a.c_str(), kUsage);
      return 2;
    }
    const std::string v = args[++i];
    char* end = nullptr;
    const double x = std::strtod(v.c_str(), &end);
    const bool number = end && *end == '\0' && std::isfinite(x);
    if (a == "--case") {
      kind = v;
    } else if (a == "--out") {
      out_dir = v;
    } else if (a == "--length-mm" && number && x >= 10 && x <= 150) {
      c.length_mm = x;
    } else if (a == "--deflection-mm" && number && x > 0) {
      c.deflection_mm = x;
    } else if (a == "--segments" && number && x >= 30 && x <= 2000) {
      c.segments = static_cast<int>(x);
    } else if (a == "--substeps" && number && x >= 1 && x <= 64) {
      c.substeps = static_cast<int>(x);
    } else {
      std::fprintf(stderr, "pcisim-bench wire-force: bad option %s %s\n%s", a.c_str(), v.c_str(), kUsage);
      return 2;
    }
  }
  if (!kind.empty() && kind != "tip_on_wall") {
    std::fprintf(stderr, "pcisim-bench wire-force: --case %s is not built (only tip_on_wall)\n", kind.c_str());
    return 2;
  }
  if (c.deflection_mm > 0.3 * c.length_mm) {
    std::fprintf(stderr, "pcisim-bench wire-force: --deflection-mm must be at most 0.3 x --length-mm\n");
    return 2;
  }
  if (kind == "tip_on_wall") {
    std::printf("%s\n", json_line(c, run_tip_on_wall(c)).c_str());
    return 0;
  }
  // the sweep
  std::vector<std::pair<TipOnWall, TipOnWallResult>> rows;
  for (const double ratio : {0.01, 0.05, 0.1, 0.2, 0.3}) {
    TipOnWall s;
    s.deflection_mm = ratio * s.length_mm;
    rows.push_back({s, run_tip_on_wall(s)});
    std::printf("%s\n", json_line(s, rows.back().second).c_str());
  }
  // held out: lengths the finger rig and the warm start were never tuned on (48 mm was)
  for (const double length_mm : {30.0, 100.0}) {
    TipOnWall s;
    s.length_mm = length_mm;
    s.deflection_mm = 0.2 * length_mm;
    rows.push_back({s, run_tip_on_wall(s)});
    std::printf("%s\n", json_line(s, rows.back().second).c_str());
  }
  for (const int segments : {75, 150, 600}) {
    TipOnWall s;
    s.deflection_mm = 0.1 * s.length_mm;
    s.segments = segments;
    rows.push_back({s, run_tip_on_wall(s)});
    std::printf("%s\n", json_line(s, rows.back().second).c_str());
  }
  std::filesystem::create_directories(out_dir);
  {
    std::ofstream json(std::filesystem::path(out_dir) / "wire-force.json");
    json << "{\"machine\": \"" << machine_info() << "\", \"runs\": [\n";
    for (size_t i = 0; i < rows.size(); ++i)
      json << "  " << json_line(rows[i].first, rows[i].second) << (i + 1 < rows.size() ? ",\n" : "\n");
    json << "]}\n";
  }
  std::ofstream md(std::filesystem::path(out_dir) / "wire-force.md");
  md << "# The wire's forces against mechanics\n\n"
     << "Generated by `pcisim-bench wire-force` (bench/wire_force_bench.cc) on " << machine_info() << ".\n\n"
     << "The rod wire with its wall inside the solve (`RodContactScheme::kSolve`, issue #33; docs/guidewire.md). "
        "**tip_on_wall**: a uniform wire (EI 1.56e-5 N m², no soft tip) fed 48 mm out of a straight catheter (whole "
        "segments at every resolution below), its tip pushed sideways D by a rigid frictionless finger (its face a "
        "plane, its edge kept 0.4 mm behind the tip so that only the tip meets it) over 3 s and held 2 s; the force is "
        "the finger's over the last 0.5 s. "
        "References, computed by the bench from the textbook, not from the rod: the small-deflection cantilever "
        "3 EI D / L³, and the exact elastica under a dead tip load perpendicular to the clamp (physics/rod/"
        "elastica.h, shooting, checked against Bisshopp-Drucker; the bench inverts it for the load that deflects the "
        "tip by D). Error: against the elastica; the small-deflection column is the simplest model beside it (the "
        "trivial one, no deflection, has no force at all). L 30 and 100 mm are held out: the rig and the warm start "
        "were tuned at 48 mm. Target (issue #33): within 3 % for D up to 0.3 L. ms: one 30 Hz "
        "step of the wire (8 substeps), median / p99 over the 5 s. The contact solve applies the last substep's "
        "impulses before it finds the contacts (docs/guidewire.md): without that, the tip's free spring-back put the "
        "node behind it against the finger at D = 0.2 L and the force was 6 % high (18 % at 0.3 L).\n\n"
     << "| L mm | D mm | D / L | segments | force N | 3EID/L³ N | elastica N | error % | target | residual mm | "
        "ms p50 / p99 |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [s, r] : rows) {
    const double err = 100.0 * (r.contact_force_n / r.elastica_n - 1.0);
    md << fmt::format(
        "| {:.0f} | {:.1f} | {:.2f} | {} | {:.4e} | {:.4e} | {:.4e} | {:+.2f} | {} | {:.2g} | {:.2f} / "
        "{:.2f} |\n",
        s.length_mm, s.deflection_mm, s.deflection_mm / s.length_mm, s.segments, r.contact_force_n, r.beam_n,
        r.elastica_n, err, std::abs(err) <= 3.0 ? "met" : "missed", r.residual_mm, r.step_ms_p50, r.step_ms_p99);
  }
  md << "\n**Not built yet** (issue #33): `capstan` (a wire of negligible bending stiffness pulled through a bent "
        "tube, pull = hold e^(mu theta)) and `end_on` (Euler buckling in a straight tube of small clearance). Both "
        "need the wall inside the solve on a curved wall or a buckling wire, where the scheme is not yet stable "
        "(docs/guidewire.md, \"Wall contact inside the solve\"); the dead-end figures and their plot wait on the "
        "same.\n";
  std::printf("wire-force: wrote %s/wire-force.md and .json\n", out_dir.c_str());
  return 0;
}

const bool registered = add("wire-force", "the rod wire's contact forces against beam theory and the elastica", run);

}  // namespace
}  // namespace pcisim::bench
