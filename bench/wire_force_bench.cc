// pcisim-bench wire-force: the rod wire's forces against mechanics the bench does not compute
// itself (issue #33), with the wall inside the rod's solve (RodContactScheme::kSolve, or kImplicit with
// --contact implicit). The rigs
// (wire_force_rigs.h, one file each): tip_on_wall (the elastica's tip load), capstan (Euler's
// capstan equation), end_on (Euler's clamped-pinned buckling load), dead_end (the default
// wire pushed into a closed tube: the hub's force against the feed, for the report's plot) and
// torque_lag (the tip's spin against the hub's turn).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench/bench_options.h"
#include "bench/bench_registry.h"
#include "bench/machine_info.h"
#include "bench/wire_force_rigs.h"

namespace pcisim::bench {
namespace {

using namespace wire_force;

constexpr const char* kUsage =
    "pcisim-bench wire-force --case CASE [options]: one run, one JSON line\n"
    "  --case tip_on_wall [--length-mm L (48)] [--deflection-mm D (4.8)] [--segments N (300)] [--substeps S (8)]\n"
    "      a wire of free length L (10-150 mm; whole segments of the 300 mm wire, else rounded up), its tip pushed\n"
    "      sideways D (0 < D <= 0.3 L) by a frictionless finger: the finger's force (contact_force_n), the wire's EI\n"
    "      (ei_nm2), 3 EI D / L^3 (beam_n) and the elastica's load for that deflection (elastica_n)\n"
    "  --case capstan [--mu M (0.2, 0.05-0.4)] [--angle-deg A (90, 10-360)] [--hold-n H (0.05, 0.01-1)]\n"
    "      a wire of negligible bending stiffness drawn round a tube bent by A (a helix beyond 180), held at its far\n"
    "      end by H and pulled back by the hub: pull_n and hold_n against capstan_n = H e^(M wrap_rad)\n"
    "  --case end_on [--length-mm L (50, 20-150, whole mm)] [--clearance-mm C (0.5, 0.1-1)]\n"
    "      a straight wire pushed into the closed end of a straight tube of radial clearance C: buckling_n (the hub's\n"
    "      force when it first buckles) against euler_n (clamped-pinned), max_hub_n over 20 mm more feed\n"
    "  --case dead_end\n"
    "      the default wire fed into the closed end of a bent tube: the hub's force against the feed (curve)\n"
    "  --case torque_lag [--path tortuous|straight (tortuous)] [--friction on|off (on)] [--fed-mm F (130, 60-140)]\n"
    "      (the tortuous tube's last bend ends 115.5 mm in: fed less, the tip stops short of it)\n"
    "      the hub turned 360 deg at 180 deg/s, then held 2 s: the tip's spin against time (curve), the lag when the\n"
    "      hub stops and after the hold, the tip's fastest turn / the hub's rate (> 1: whip). Straight and\n"
    "      frictionless, the tip follows the hub (the baseline)\n"
    "  --case default_scene\n"
    "      the default beating scene with the rod as its wire (200 segments, the moving wall pushing it), driven by\n"
    "      the built-in trainee's session down the LAD: the wire's cost a step (issue #33: 3 ms at p99 with the\n"
    "      contact inside), once with the wall after the rod's solve (projection) and once inside it (--contact)\n"
    "  every case: [--contact solve|implicit (solve)]: the contact problem on the rod's compliance after its free\n"
    "      solve, or the wall as a stiff one-sided spring inside the rod's solve (RodContactScheme)\n"
    "pcisim-bench wire-force [--out DIR (docs/benchmarks)] [--no-plot] [--quick]\n"
    "  the sweep: every case over the ranges above; wire-force.md, .json and .png (the plot: matplotlib);\n"
    "  with --contact implicit, wire-force-implicit.md, .json and .png.\n"
    "  --quick: one run of each case\n";

// a number option within [lo, hi], else an error naming it
bool number_in(const std::string& flag, const std::string& v, double lo, double hi, double* out) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (!(end && *end == '\0' && std::isfinite(x) && x >= lo && x <= hi)) {
    std::fprintf(stderr, "pcisim-bench wire-force: %s must be a number in [%g, %g], not '%s'\n", flag.c_str(), lo, hi,
                 v.c_str());
    return false;
  }
  *out = x;
  return true;
}

int one_case(const std::vector<std::string>& args) {
  std::string kind;
  TipOnWall tip;
  Capstan cap;
  EndOn end;
  TorqueLag lag;
  bool length_given = false;
  double length_mm = 0;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (i + 1 >= args.size()) {
      std::fprintf(stderr, "pcisim-bench wire-force: %s needs a value\n%s", a.c_str(), kUsage);
      return 2;
    }
    const std::string& v = args[++i];
    double x = 0;
    bool ok = true;
    if (a == "--case") {
      kind = v;
    } else if (a == "--length-mm") {
      ok = number_in(a, v, 10, 150, &length_mm);
      length_given = true;
    } else if (a == "--deflection-mm") {
      ok = number_in(a, v, 1e-3, 45, &tip.deflection_mm);
    } else if (a == "--segments") {
      ok = number_in(a, v, 30, 2000, &x);
      tip.segments = static_cast<int>(x);
    } else if (a == "--substeps") {
      ok = number_in(a, v, 1, 64, &x);
      tip.substeps = static_cast<int>(x);
    } else if (a == "--mu") {
      ok = number_in(a, v, 0.05, 0.4, &cap.mu);
    } else if (a == "--angle-deg") {
      ok = number_in(a, v, 10, 360, &cap.angle_deg);
    } else if (a == "--hold-n") {
      ok = number_in(a, v, 0.01, 1, &cap.hold_n);
    } else if (a == "--clearance-mm") {
      ok = number_in(a, v, 0.1, 1, &end.clearance_mm);
    } else if (a == "--path" && (v == "tortuous" || v == "straight")) {
      lag.tortuous = v == "tortuous";
    } else if (a == "--friction" && (v == "on" || v == "off")) {
      lag.friction = v == "on";
    } else if (a == "--fed-mm") {
      ok = number_in(a, v, 60, 140, &lag.fed_mm);
    } else if (a == "--path" || a == "--friction") {
      std::fprintf(stderr, "pcisim-bench wire-force: %s must be %s, not '%s'\n", a.c_str(),
                   a == "--path" ? "tortuous or straight" : "on or off", v.c_str());
      return 2;
    } else {
      std::fprintf(stderr, "pcisim-bench wire-force: unknown option %s\n%s", a.c_str(), kUsage);
      return 2;
    }
    if (!ok) return 2;
  }
  if (kind == "tip_on_wall") {
    if (length_given) tip.length_mm = length_mm;
    if (tip.deflection_mm > 0.3 * tip.length_mm) {
      std::fprintf(stderr, "pcisim-bench wire-force: --deflection-mm must be at most 0.3 x --length-mm\n");
      return 2;
    }
    std::printf("%s\n", json_line(tip, run_tip_on_wall(tip)).c_str());
  } else if (kind == "capstan") {
    std::printf("%s\n", json_line(cap, run_capstan(cap)).c_str());
  } else if (kind == "end_on") {
    if (length_given) {
      if (length_mm < 20 || length_mm != std::round(length_mm)) {
        std::fprintf(stderr, "pcisim-bench wire-force: --length-mm for end_on must be whole mm in [20, 150]\n");
        return 2;
      }
      end.length_mm = length_mm;
    }
    std::printf("%s\n", json_line(end, run_end_on(end)).c_str());
  } else if (kind == "dead_end") {
    std::printf("%s\n", json_line(run_dead_end()).c_str());
  } else if (kind == "torque_lag") {
    std::printf("%s\n", json_line(lag, run_torque_lag(lag)).c_str());
  } else if (kind == "default_scene") {
    std::printf("%s\n", json_line(run_default_scene(physics::RodContactScheme::kProjection)).c_str());
    std::printf("%s\n", json_line(run_default_scene(contact_scheme())).c_str());
  } else {
    std::fprintf(
        stderr,
        "pcisim-bench wire-force: --case must be tip_on_wall, capstan, end_on, dead_end, torque_lag or default_scene, "
        "not '%s'\n",
        kind.c_str());
    return 2;
  }
  return 0;
}

const char* met(double error_pct) {
  return std::abs(error_pct) <= 3.0 ? "met" : "missed";
}

int run(const std::vector<std::string>& given) {
  // --contact picks the wall scheme of every rig, then the rest as usual
  std::vector<std::string> args;
  for (size_t i = 0; i < given.size(); ++i) {
    if (given[i] != "--contact") {
      args.push_back(given[i]);
      continue;
    }
    const std::string v = i + 1 < given.size() ? given[++i] : "";
    if (v != "solve" && v != "implicit") {
      std::fprintf(stderr, "pcisim-bench wire-force: --contact must be solve or implicit, not '%s'\n", v.c_str());
      return 2;
    }
    set_contact_scheme(v == "solve" ? physics::RodContactScheme::kSolve : physics::RodContactScheme::kImplicit);
  }
  if (std::find(args.begin(), args.end(), "--case") != args.end()) return one_case(args);
  BenchOptions bo;
  if (const int rc = parse_bench_options(args, "wire-force", kUsage, &bo); rc >= 0) return rc;
  std::vector<std::string> lines;
  auto keep = [&](const std::string& line) {
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
    lines.push_back(line);
  };
  // tip on a wall: D / L at 48 mm, then L 30 and 100 mm held out, then the segment length
  std::vector<std::pair<TipOnWall, TipOnWallResult>> tips;
  std::vector<TipOnWall> tip_cases;
  for (const double ratio : bo.quick ? std::vector<double>{0.2} : std::vector<double>{0.01, 0.05, 0.1, 0.2, 0.3}) {
    TipOnWall s;
    s.deflection_mm = ratio * s.length_mm;
    tip_cases.push_back(s);
  }
  if (!bo.quick) {
    for (const double length_mm : {30.0, 100.0}) {
      TipOnWall s;
      s.length_mm = length_mm;
      s.deflection_mm = 0.2 * length_mm;
      tip_cases.push_back(s);
    }
    for (const int segments : {75, 150, 600}) {
      TipOnWall s;
      s.deflection_mm = 0.1 * s.length_mm;
      s.segments = segments;
      tip_cases.push_back(s);
    }
  }
  for (const TipOnWall& s : tip_cases) {
    tips.push_back({s, run_tip_on_wall(s)});
    keep(json_line(s, tips.back().second));
  }
  // capstan: tuned at 90 degrees with mu 0.1 and 0.3; the other angles and coefficients held out
  std::vector<std::pair<Capstan, CapstanResult>> caps;
  for (const double angle : bo.quick ? std::vector<double>{90} : std::vector<double>{90, 180, 360})
    for (const double mu : bo.quick ? std::vector<double>{0.2} : std::vector<double>{0.05, 0.1, 0.2, 0.4}) {
      Capstan c;
      c.mu = mu;
      c.angle_deg = angle;
      caps.push_back({c, run_capstan(c)});
      keep(json_line(c, caps.back().second));
    }
  // end on
  std::vector<std::pair<EndOn, EndOnResult>> ends;
  for (const double length : bo.quick ? std::vector<double>{50} : std::vector<double>{30, 50, 100})
    for (const double clearance : bo.quick ? std::vector<double>{0.5} : std::vector<double>{0.1, 0.5, 1.0}) {
      EndOn e;
      e.length_mm = length;
      e.clearance_mm = clearance;
      ends.push_back({e, run_end_on(e)});
      keep(json_line(e, ends.back().second));
    }
  const DeadEndResult dead = run_dead_end();
  keep(json_line(dead));
  // torque lag: the tortuous tube with and without friction, and the straight frictionless baseline
  std::vector<std::pair<TorqueLag, TorqueLagResult>> lags;
  for (const auto& [tortuous, friction] :
       bo.quick ? std::vector<std::pair<bool, bool>>{{true, true}}
                : std::vector<std::pair<bool, bool>>{{false, false}, {true, false}, {true, true}}) {
    TorqueLag l;
    l.tortuous = tortuous;
    l.friction = friction;
    lags.push_back({l, run_torque_lag(l)});
    keep(json_line(l, lags.back().second));
  }
  // the default scene: the wall after the rod's solve, then inside it
  std::vector<DefaultSceneResult> scenes;
  for (const physics::RodContactScheme scheme : {physics::RodContactScheme::kProjection, contact_scheme()}) {
    scenes.push_back(run_default_scene(scheme));
    keep(json_line(scenes.back()));
  }

  std::filesystem::create_directories(bo.out_dir);
  const bool implicit = contact_scheme() == physics::RodContactScheme::kImplicit;
  const std::string stem = implicit ? "wire-force-implicit" : "wire-force";
  const std::string json_path = (std::filesystem::path(bo.out_dir) / (stem + ".json")).string();
  const std::string md_path = (std::filesystem::path(bo.out_dir) / (stem + ".md")).string();
  {
    std::ofstream json(json_path);
    json << "{\"machine\": \"" << machine_info() << "\", \"runs\": [\n";
    for (size_t i = 0; i < lines.size(); ++i) json << "  " << lines[i] << (i + 1 < lines.size() ? ",\n" : "\n");
    json << "]}\n";
  }
  std::ofstream md(md_path);
  md << "# The wire's forces against mechanics" << (implicit ? ": the wall as a spring inside the solve" : "") << "\n\n"
     << "Generated by `pcisim-bench wire-force" << (implicit ? " --contact implicit" : "")
     << "` (bench/wire_force_bench.cc, the rigs in bench/wire_force_*.cc) on " << machine_info()
     << (bo.quick ? " (--quick: one run of each case)" : "") << ".\n\n"
     << (implicit ? "The rod wire with its wall as a stiff one-sided spring inside its own solve "
                    "(`RodContactScheme::kImplicit`, issue #33; docs/guidewire.md; the contact problem after the free "
                    "solve is in wire-force.md): "
                  : "The rod wire with its wall inside the solve (`RodContactScheme::kSolve`, issue #33; "
                    "docs/guidewire.md): ")
     << "each rig's reference is a textbook result the bench computes without the rod. Target (issue #33): each "
        "within 3 %. ms: one 30 Hz step of the wire (8 substeps, more where the contact halved them: substeps "
        "median / most), median / p99 over the measured steps of the run, on the machine above.\n\n";
  md << "## tip_on_wall\n\nA uniform wire (EI 1.56e-5 N m², no soft tip) fed 48 mm out of a straight catheter (whole "
        "segments at every resolution below), its tip pushed sideways D by a rigid frictionless finger (its face a "
        "plane, its edge kept 0.4 mm behind the tip so that only the tip meets it) over 3 s and held 2 s; the force "
        "is the finger's over the last 0.5 s. References: the small-deflection cantilever 3 EI D / L³ and the exact "
        "elastica under a dead tip load perpendicular to the clamp (physics/rod/elastica.h, shooting, checked against "
        "Bisshopp-Drucker; inverted for the load that deflects the tip by D). Error: against the elastica; the "
        "small-deflection column is the simplest model beside it. L 30 and 100 mm are held out (the rig was tuned at "
        "48 mm).\n\n"
     << "| L mm | D mm | D / L | segments | force N | 3EID/L³ N | elastica N | error % | target | residual mm | "
        "ms p50 / p99 | substeps |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [s, r] : tips) {
    const double err = 100.0 * (r.contact_force_n / r.elastica_n - 1.0);
    md << fmt::format(
        "| {:.0f} | {:.1f} | {:.2f} | {} | {:.4e} | {:.4e} | {:.4e} | {:+.2f} | {} | {:.2g} | {:.2f} / "
        "{:.2f} | {} / {} |\n",
        s.length_mm, s.deflection_mm, s.deflection_mm / s.length_mm, s.segments, r.contact_force_n, r.beam_n,
        r.elastica_n, err, met(err), r.residual_mm, r.cost.ms_p50, r.cost.ms_p99, r.cost.substeps_p50,
        r.cost.substeps_max);
  }
  md << "\n## capstan\n\nA wire of negligible bending stiffness (EI and GJ 1e-9, the range's floor; no soft tip; "
        "300 segments) drawn by a 0.01 N leader force on its tip through a tube (1.5 mm lumen radius) that runs 30 mm "
        "straight, bends by the angle at 15 mm radius (beyond 180° a helix rising 5 mm a turn, the entry straight "
        "along its start: no kink for the wire to wrap) and runs 40 mm straight; the catheter's exit on the bend's "
        "inner side, so the taut wire wraps the whole bend. Its tip then "
        "held by 0.05 N along the last straight while the hub pulls it back at 10 mm/s for 1.5 s; pull: the hub's "
        "force averaged over every substep of the last 0.75 s (spread: the largest departure of one step's average "
        "from it; at step ends: the force at each step's last substep, what a 30 Hz reader of the hub's force sees, "
        "mean over those steps: where successive substeps alternate it differs from the average). Reference: Euler's "
        "capstan equation, pull = hold e^(μ θ), θ the angle the wire's tangent turns (the bend's; on the helix "
        "θ a / √(a² + c²), a the wire's helix radius, c its rise per radian: 0.2 % less at 360°). The trivial "
        "model, a wire without friction, pulls with the hold. Tuned at 90° with μ 0.1 and 0.3; the rest are held "
        "out.\n\n"
     << "| angle ° | μ | hold N | pull N | spread N | at step ends N | e^(μθ) hold N | error % | target | "
        "residual mm | ms p50 / p99 | substeps |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [c, r] : caps) {
    const double err = 100.0 * (r.pull_n / r.capstan_n - 1.0);
    if (!r.drawn_through) {
      md << fmt::format("| {:.0f} | {:.2f} | {:.2f} | not drawn through | | | | | missed | | | |\n", c.angle_deg, c.mu,
                        c.hold_n);
      continue;
    }
    md << fmt::format(
        "| {:.0f} | {:.2f} | {:.2f} | {:.5f} | {:.2g} | {:.5f} | {:.5f} | {:+.2f} | {} | {:.3f} | {:.1f} / {:.1f} | "
        "{} / {} |\n",
        c.angle_deg, c.mu, c.hold_n, r.pull_n, r.pull_spread_n, r.pull_step_end_n, r.capstan_n, err, met(err),
        r.residual_mm, r.cost.ms_p50, r.cost.ms_p99, r.cost.substeps_p50, r.cost.substeps_max);
  }
  md << "\n## end_on\n\nA straight wire (EI 1.56e-5 N m², no soft tip, no friction) in a straight tube closed at the "
        "far end, the catheter's exit on its axis; the lumen radius is the clearance plus the wall margin (0.05 mm), "
        "so the wire's centerline may move the clearance off the axis. Fed until its tip meets the end at free "
        "length L (the last millimetre at 5 mm/s), then loaded: the hub's force raised by 0.02 EI / L² a step (0.1 % "
        "of Euler's load), the feed moved by half the column's axial compliance L / EA times the shortfall (a rigid "
        "push overshoots Euler's load within a substep: 1 µm is 0.2 N at 30 mm) until it buckles, then 20 mm more "
        "at 5 mm/s; a lateral gravity of 0.05 m/s² is the imperfection. Buckling: the "
        "hub's force when the wire's largest lateral deflection first reaches half the clearance. Reference: the "
        "clamped (catheter) – pinned (the end's cap) Euler load 4.4934² EI / L² = π² EI / (0.699 L)² (Timoshenko & "
        "Gere 2.6), L the column from the hub node (the rod's clamp, up to a segment behind the exit) to the end's "
        "stop; the post-buckling elastica adds under 0.1 % at these deflections. max hub, crumpled and worst: "
        "over the whole run (approach, load and the 20 mm push) up to where it blew up (blew up: a hub force over "
        "50 N, the tip thrown back out of the tube's end, or the rod recovered after going non-finite); worst: the "
        "furthest a node went past the wall margin.\n\n"
     << "| L mm | clearance mm | buckling N | Euler N | error % | target | max hub N | crumpled mm | blew up at mm | "
        "worst mm | ms p50 / p99 | substeps |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [e, r] : ends) {
    const double err = 100.0 * (r.buckling_n / r.euler_n - 1.0);
    md << fmt::format(
        "| {:.0f} | {:.1f} | {} | {:.5f} | {} | {} | {:.4f} | {:.3f} | {} | {:+.4f} | {:.1f} / {:.1f} | {} / {} |\n",
        e.length_mm, e.clearance_mm, r.buckled ? fmt::format("{:.5f}", r.buckling_n) : "none", r.euler_n,
        r.buckled ? fmt::format("{:+.2f}", err) : "", r.buckled ? met(err) : "missed", r.max_hub_n, r.max_crumpled_mm,
        r.blew_up_at_mm < 0 ? std::string("never") : fmt::format("{:.2f}", r.blew_up_at_mm), r.worst_mm, r.cost.ms_p50,
        r.cost.ms_p99, r.cost.substeps_p50, r.cost.substeps_max);
  }
  md << "\n## dead_end\n\nThe default wire (EI 1.56e-5 N m², 12 mm soft tip of 4e-7 N m², straight) with friction "
        "0.3 / 0.2 in the rod tests' bent tube (40 mm straight, 90° at 15 mm radius, closed 124 mm along its "
        "centerline; 1.5 mm lumen radius), fed 110 mm, then on towards 200 mm over 3 s and held 1 s; the grip "
        "slips above 1 N (`feed_refuse_force_n`). Targets (issue #33): nothing crumples (the free wire's length kept "
        "within 1 %, 1.2 mm here), the hub's force bounded and continuous, penetration ≤ 0.05 mm at 1 N.\n\n"
     << fmt::format("- hub force: at most {:.3f} N; the largest change between two steps {:.3f} N\n", dead.max_hub_n,
                    dead.largest_hub_jump_n)
     << fmt::format("- tip force on the end: at most {:.3f} N\n", dead.max_tip_n)
     << fmt::format("- crumpled: at most {:.3f} mm ({})\n", dead.max_crumpled_mm,
                    dead.max_crumpled_mm <= 1.24 ? "met" : "missed")
     << fmt::format("- past the wall margin: at most {:+.4f} mm ({})\n", dead.worst_mm,
                    dead.worst_mm <= 0.05 ? "met" : "missed")
     << fmt::format("- refused at the end: {:.1f} mm of the 200 commanded\n", dead.refused_mm)
     << fmt::format("- ms a step: {:.1f} / {:.1f} (p50 / p99), substeps {} / {}\n", dead.cost.ms_p50, dead.cost.ms_p99,
                    dead.cost.substeps_p50, dead.cost.substeps_max);
  md << "\n## torque_lag\n\nThe default wire (EI 1.56e-5 N m², 12 mm soft tip, straight) fed 130 mm at 30 mm/s into a "
        "tube of 1.5 mm lumen radius, settled 0.5 s, then the hub turned 360° at 180°/s and held 2 s. Tortuous: 32 mm "
        "straight, bends of 90°, 90° and 120° at 10–12 mm radius in three planes with 15 mm straights between them, "
        "then straight (the last bend ends 115.5 mm along the centerline from the catheter's exit: the tip "
        "14.5 mm past it). The tip's spin: its material frame's turn about its own "
        "tangent, step by step, the tangent's own turn taken out (the old frame carried to the new tangent by the "
        "smallest rotation). No textbook value: the straight frictionless tube is the check of the measure (the tip "
        "follows the hub); the tortuous tube shows what friction does (issue #33 item 5: lag and whip). Whip: the "
        "tip's fastest turn over one step against the hub's rate.\n\n"
     << "| tube | friction | lag when the hub stops ° | after the 2 s hold ° | most lag ° | most lead ° | fastest tip "
        "/ hub | ms p50 / p99 | substeps |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [l, r] : lags) {
    if (!r.completed) {
      md << fmt::format("| {} | {} | went non-finite (recovered) | | | | | | |\n", l.tortuous ? "tortuous" : "straight",
                        l.friction ? "on" : "off");
      continue;
    }
    md << fmt::format("| {} | {} | {:+.2f} | {:+.2f} | {:.2f} | {:.2f} | {:.2f} | {:.1f} / {:.1f} | {} / {} |\n",
                      l.tortuous ? "tortuous" : "straight", l.friction ? "0.1 / 0.07 body, 0.2 / 0.15 tip" : "none",
                      r.lag_at_turn_end_deg, r.final_lag_deg, r.max_lag_deg, r.max_lead_deg, r.max_tip_rate_ratio,
                      r.cost.ms_p50, r.cost.ms_p99, r.cost.substeps_p50, r.cost.substeps_max);
  }
  md << "\n## default_scene\n\nThe default beating scene (heart, moving tree, pulsatile blood, friction 0.1 / 0.07 "
        "body, 0.2 / 0.15 tip, SDF 0.2 mm) driven by the built-in trainee's 19.5 s session down the LAD, its wire the "
        "rod as `guidewire.model \"rod\"` gives it (200 segments, the moving wall pushing it: `beat_coupling` "
        "`contact`). No textbook value: the wire's cost a 30 Hz step where the product runs it (the world's "
        "`guidewire` effect: the rod's substeps with their contact and friction). Issue #33's target: 3 ms at p99 "
        "with the contact inside (`rod_contact` `solve`).\n\n"
     << "Halved: the steps with a substep taken back and tried at half the length, and how many substeps "
        "were retried; deep: steps that left a node more than 0.3 mm in the wall before it was moved out.\n\n"
     << "| wall | ms p50 / p99 / max | target | substeps p50 / max | halved steps / retried substeps | deepest left in "
        "the "
        "wall mm | deep steps | most hub N | recoveries |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const DefaultSceneResult& r : scenes) {
    const bool inside = r.scheme != physics::RodContactScheme::kProjection;
    // (the projection moves nodes out without measuring how deep: no figure)
    md << fmt::format("| {} | {:.2f} / {:.2f} / {:.2f} | {} | {} / {} | {} of {} / {} | {} | {} | {:.3f} | {} |\n",
                      inside ? (implicit ? "inside (implicit)" : "inside (solve)") : "after (projection)",
                      r.cost.ms_p50, r.cost.ms_p99, r.max_ms, inside ? (r.cost.ms_p99 <= 3.0 ? "met" : "missed") : "—",
                      r.cost.substeps_p50, r.cost.substeps_max, r.steps_halved, r.steps, r.retried,
                      inside ? fmt::format("{:.4f}", r.max_residual_mm) : std::string("—"),
                      inside ? fmt::format("{}", r.deep_steps) : std::string("—"), r.max_hub_n, r.recoveries);
  }
  md.close();
  if (bo.plot && std::filesystem::exists("docs/benchmarks/wire-force.py")) {
    if (run_plot_script("wire-force",
                        "docs/benchmarks/wire-force.py " + json_path + " " + bo.out_dir + "/" + stem + ".png"))
      std::ofstream(md_path, std::ios::app)
          << "\n![the dead end, the capstan, end on and the torque lag](" << stem << ".png)\n";
  }
  std::printf("wire-force: wrote %s and %s\n", md_path.c_str(), json_path.c_str());
  return 0;
}

const bool registered =
    add("wire-force", "the rod wire's contact forces against the elastica, the capstan and Euler buckling", run);

}  // namespace
}  // namespace pcisim::bench
