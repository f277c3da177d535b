#include "server/debrief/debrief_page.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <vector>

#include "png/png_gray.h"

namespace pcisim::server {
namespace {

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string base64(const std::vector<uint8_t>& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const uint32_t n = static_cast<uint32_t>(bytes[i]) << 16 |
                       (i + 1 < bytes.size() ? static_cast<uint32_t>(bytes[i + 1]) << 8 : 0u) |
                       (i + 2 < bytes.size() ? static_cast<uint32_t>(bytes[i + 2]) : 0u);
    out += table[n >> 18 & 63];
    out += table[n >> 12 & 63];
    out += i + 1 < bytes.size() ? table[n >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? table[n & 63] : '=';
  }
  return out;
}

// a figure of a debrief.json as text ("—" where it is null or absent)
std::string value_text(const nlohmann::json& j, const std::string& key, int decimals) {
  if (!j.contains(key) || j.at(key).is_null()) return "—";
  const nlohmann::json& v = j.at(key);
  if (v.is_number_integer()) return fmt::format("{}", v.get<int64_t>());
  if (v.is_number()) return fmt::format("{:.{}f}", v.get<double>(), decimals);
  if (v.is_string()) return escape(v.get<std::string>());
  return "—";
}

struct Row {
  const char* key;
  const char* label;
  int decimals;
  const char* source;  // who reports it, or what it shows
};

// the figures, as validation studies and the lab report them (docs/debrief.md defines each)
const Row kRows[] = {
    {"procedure_time_s", "Procedure time (s)", 1, "Gallagher 2006"},
    {"fluoro_time_s", "Fluoroscopy time, beam on (s)", 1, "Gallagher 2006, Jensen 2016"},
    {"cine_runs", "Cine runs", 0, "Gallagher 2006"},
    {"contrast_ml", "Contrast (ml)", 1, "Gallagher 2006"},
    {"contrast_injections", "Injections", 0, ""},
    {"air_kerma_mgy", "Air kerma at the reference point (mGy)", 2, "assumed technique"},
    {"dap_gycm2", "Dose-area product (Gy cm²)", 3, "assumed technique"},
    {"tip_path_mm", "Tip path (mm)", 0, "Rolls 2017 (in pixels)"},
    {"tip_path_projected_mm", "Tip path across the beam (mm)", 0, "as on the image"},
    {"tip_path_in_vessels_mm", "Tip path through the vessels (mm)", 0, "the heart's motion taken out"},
    {"wrong_branch_s", "Time off the route to the target (s)", 1, "simulator truth"},
    {"target_reached_s", "Target reached at (s)", 1, "simulator truth"},
    {"peak_tip_force_n", "Peak tip force on the wall (N)", 3, "simulator truth (rod wire)"},
    {"tip_force_above_threshold_s", "Time above the force threshold (s)", 1, "simulator truth (rod wire)"},
    {"force_events", "Force events above the risk force", 0, "simulator truth (rod wire)"},
    {"prolapse_events", "Prolapses (the wire folded back)", 0, "simulator truth"},
    {"buckling_events", "Buckling (the feed not reaching the tip)", 0, "simulator truth"},
};

std::string figures_table(const nlohmann::json& trainee, const nlohmann::json* reference) {
  std::string s = "<table><tr><th>figure</th><th>this session</th>";
  if (reference) s += "<th>reference</th>";
  s += "<th>source</th></tr>\n";
  for (const Row& r : kRows) {
    s += fmt::format("<tr><td>{}</td><td class=n>{}</td>", r.label, value_text(trainee, r.key, r.decimals));
    if (reference) s += fmt::format("<td class=n>{}</td>", value_text(*reference, r.key, r.decimals));
    s += fmt::format("<td class=src>{}</td></tr>\n", r.source);
  }
  return s + "</table>\n";
}

// the session's events on one time axis: rows for the beam, contrast, C-arm moves, the tip off its
// route and force events
std::string timeline_svg(const DebriefFigures& f) {
  double end_s = std::max(f.procedure_time_s, 1.0);
  for (const TimelineEntry& e : f.timeline) end_s = std::max(end_s, e.time_s);
  const double left = 150, width = 760, row_h = 26;
  const auto x_of = [&](double t) { return left + width * std::clamp(t / end_s, 0.0, 1.0); };
  const char* rows[] = {"fluoroscopy",   "cine",         "contrast",          "C-arm",
                        "tip off route", "force events", "prolapse, buckling"};
  const int n_rows = 7;
  std::string s = fmt::format(R"(<svg class="timeline" width="{}" height="{}" xmlns="http://www.w3.org/2000/svg">)",
                              left + width + 20, row_h * n_rows + 40);
  for (int r = 0; r < n_rows; ++r)
    s += fmt::format(R"(<text x="4" y="{}" class="lab">{}</text><line x1="{}" x2="{}" y1="{}" y2="{}" class="grid"/>)",
                     row_h * r + 18, rows[r], left, left + width, row_h * r + row_h, row_h * r + row_h);
  // beam rows: bars from on to off
  const auto bars = [&](TimelineKind on, TimelineKind off, int row, const char* cls) {
    double start = -1.0;
    for (const TimelineEntry& e : f.timeline) {
      if (e.kind == on && start < 0.0) start = e.time_s;
      if (e.kind == off && start >= 0.0) {
        s += fmt::format(R"(<rect x="{:.1f}" y="{}" width="{:.1f}" height="14" class="{}"/>)", x_of(start),
                         row_h * row + 6, std::max(x_of(e.time_s) - x_of(start), 1.0), cls);
        start = -1.0;
      }
    }
    if (start >= 0.0)
      s += fmt::format(R"(<rect x="{:.1f}" y="{}" width="{:.1f}" height="14" class="{}"/>)", x_of(start),
                       row_h * row + 6, std::max(x_of(end_s) - x_of(start), 1.0), cls);
  };
  bars(TimelineKind::kFluoroOn, TimelineKind::kFluoroOff, 0, "fluoro");
  bars(TimelineKind::kCineOn, TimelineKind::kCineOff, 1, "cine");
  for (const TimelineEntry& e : f.timeline) {
    const double x = x_of(e.time_s);
    if (e.kind == TimelineKind::kContrast)
      s += fmt::format(
          R"(<path d="M{:.1f} {} l6 12 h-12 z" class="contrast"><title>{:.0f} ml at {:.1f} s</title></path>)", x,
          row_h * 2 + 6, e.a, e.time_s);
    if (e.kind == TimelineKind::kCArm)
      s += fmt::format(
          R"(<line x1="{:.1f}" x2="{:.1f}" y1="{}" y2="{}" class="carm"/><text x="{:.1f}" y="{}" class="small">{} {:.0f} / {} {:.0f}</text>)",
          x, x, row_h * 3 + 4, row_h * 3 + 22, x + 3, row_h * 3 + 17, e.a < 0 ? "RAO" : "LAO", std::abs(e.a),
          e.b < 0 ? "CAU" : "CRA", std::abs(e.b));
    if (e.kind == TimelineKind::kForceEvent)
      s += fmt::format(
          R"(<circle cx="{:.1f}" cy="{}" r="{:.1f}" class="force"><title>{:.3f} N for {:.2f} s at {:.1f} s</title></circle>)",
          x, row_h * 5 + 13, 4.0 + 20.0 * std::min(e.a, 0.5), e.a, e.b, e.time_s);
    if (e.kind == TimelineKind::kProlapse || e.kind == TimelineKind::kBuckling)
      s += fmt::format(
          R"(<rect x="{:.1f}" y="{}" width="{:.1f}" height="14" class="{}"><title>{} for {:.1f} s at {:.1f} s</title></rect>)",
          x, row_h * 6 + 6, std::max(x_of(e.time_s + e.b) - x, 2.0),
          e.kind == TimelineKind::kProlapse ? "prolapse" : "buckle",
          e.kind == TimelineKind::kProlapse ? fmt::format("folded {:.0f}°", e.a)
                                            : fmt::format("{:.1f} mm of feed not taken up", e.a),
          e.b, e.time_s);
  }
  // the tip off its route: runs of track points
  double run_start = -1.0, last_t = 0.0;
  for (const TrackPoint& p : f.track) {
    if (p.off_route && run_start < 0.0) run_start = p.time_s;
    if (!p.off_route && run_start >= 0.0) {
      s += fmt::format(R"(<rect x="{:.1f}" y="{}" width="{:.1f}" height="14" class="off"/>)", x_of(run_start),
                       row_h * 4 + 6, std::max(x_of(p.time_s) - x_of(run_start), 1.0));
      run_start = -1.0;
    }
    last_t = p.time_s;
  }
  if (run_start >= 0.0)
    s += fmt::format(R"(<rect x="{:.1f}" y="{}" width="{:.1f}" height="14" class="off"/>)", x_of(run_start),
                     row_h * 4 + 6, std::max(x_of(last_t) - x_of(run_start), 1.0));
  // the time axis
  const double step = end_s > 120 ? 30 : end_s > 40 ? 10 : 5;
  for (double t = 0; t <= end_s + 1e-9; t += step)
    s += fmt::format(R"(<text x="{:.1f}" y="{}" class="small" text-anchor="middle">{:.0f} s</text>)", x_of(t),
                     row_h * n_rows + 16, t);
  return s + "</svg>\n";
}

// the tip's force on the wall against session time, with the threshold and the risk force
std::string force_svg(const DebriefFigures& f) {
  double end_s = std::max(f.procedure_time_s, 1.0), top_n = f.params.tip_force_risk_n * 1.5;
  for (const TrackPoint& p : f.track) top_n = std::max(top_n, static_cast<double>(p.tip_force_n) * 1.1);
  const double left = 60, width = 850, height = 200;
  const auto x_of = [&](double t) { return left + width * std::clamp(t / end_s, 0.0, 1.0); };
  const auto y_of = [&](double n) { return 10 + height * (1.0 - std::clamp(n / top_n, 0.0, 1.0)); };
  std::string s =
      fmt::format(R"(<svg width="{}" height="{}" xmlns="http://www.w3.org/2000/svg">)", left + width + 20, height + 40);
  for (const auto& [n, cls, label] : {std::tuple{f.params.tip_force_threshold_n, "grid", "threshold"},
                                      std::tuple{f.params.tip_force_risk_n, "risk", "risk"}})
    s += fmt::format(
        R"(<line x1="{}" x2="{}" y1="{:.1f}" y2="{:.1f}" class="{}"/><text x="4" y="{:.1f}" class="small">{} {} N</text>)",
        left, left + width, y_of(n), y_of(n), cls, y_of(n) + 4, label, n);
  s += R"(<polyline class="forceline" points=")";
  for (const TrackPoint& p : f.track) s += fmt::format("{:.1f},{:.1f} ", x_of(p.time_s), y_of(p.tip_force_n));
  s += R"("/>)";
  s += fmt::format(
      R"(<text x="{}" y="{}" class="small">0 s</text><text x="{}" y="{}" class="small" text-anchor="end">{:.0f} s</text>)",
      left, height + 30, left + width, height + 30, end_s);
  return s + "</svg>\n";
}

// the frame that showed the vessels best, windowed to 8 bits (1st to 99th percentile), with the
// tip's path projected by the frame's own geometry: green on the route, red off it; a reference
// run's path dashed
std::string angiogram_svg(const DebriefFigures& f, const nlohmann::json* reference) {
  constexpr double kPhaseWindow = 0.05;
  const Angiogram& a = f.angiogram;
  const size_t n = static_cast<size_t>(a.width) * a.height;
  if (a.time_s < 0.0 || a.pixels.size() != n || n == 0)
    return "<p>No frame showed contrast: no angiogram to draw the path on.</p>\n";
  std::vector<uint16_t> sorted(a.pixels);
  std::nth_element(sorted.begin(), sorted.begin() + n / 100, sorted.end());
  const double lo = sorted[n / 100];
  std::nth_element(sorted.begin(), sorted.begin() + n * 99 / 100, sorted.end());
  const double hi = std::max(static_cast<double>(sorted[n * 99 / 100]), lo + 1.0);
  std::vector<uint8_t> rgb(n * 3);
  for (size_t i = 0; i < n; ++i) {
    const auto g = static_cast<uint8_t>(std::lround(255.0 * std::clamp((a.pixels[i] - lo) / (hi - lo), 0.0, 1.0)));
    rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = g;
  }
  std::string s = fmt::format(
      R"(<svg class="angio" width="{}" height="{}" viewBox="0 0 {} {}" xmlns="http://www.w3.org/2000/svg"><image width="{}" height="{}" href="data:image/png;base64,{}"/>)",
      640, 640 * a.height / a.width, a.width, a.height, a.width, a.height,
      base64(png::encode_png_rgb8(a.width, a.height, rgb.data())));
  // the whole path faint (the beat carries the tip to and fro), then the states at the frame's own
  // phase of the heart joined (about once a beat: where the vessels in the frame hold the tip),
  // green on the route, red off it
  const bool beating = std::isfinite(a.heart_phase);
  const auto at_phase = [&](double phase) {
    const double d = std::abs(phase - a.heart_phase);
    return !beating || std::min(d, 1.0 - d) <= kPhaseWindow;
  };
  std::string all, run;
  int run_off = -1;
  const auto flush = [&] {
    if (!run.empty()) s += fmt::format(R"(<polyline class="{}" points="{}"/>)", run_off ? "pathoff" : "pathon", run);
    run.clear();
  };
  Eigen::Vector2d cr, last(0, 0);
  bool have_last = false;
  for (const TrackPoint& p : f.track) {
    if (p.pipeline != a.pipeline) continue;
    if (!a.geometry.project(Eigen::Vector3d(p.tip_mm[0], p.tip_mm[1], p.tip_mm[2]), &cr)) continue;
    all += fmt::format("{:.1f},{:.1f} ", cr.x(), cr.y());
    if (!at_phase(p.heart_phase)) continue;
    if (p.off_route != run_off) {
      flush();
      run_off = p.off_route;
      if (have_last) run += fmt::format("{:.1f},{:.1f} ", last.x(), last.y());  // joined to the last run
    }
    run += fmt::format("{:.1f},{:.1f} ", cr.x(), cr.y());
    last = cr;
    have_last = true;
  }
  if (!all.empty()) s += fmt::format(R"(<polyline class="pathall" points="{}"/>)", all);
  flush();
  if (reference && reference->contains("tip_track") && reference->at("tip_track").is_array()) {
    std::string points;
    for (const auto& q : reference->at("tip_track")) {
      if (!q.is_array() || q.size() < 4 || !q[1].is_number() || !q[2].is_number() || !q[3].is_number()) continue;
      if (q.size() >= 7 && q[6].is_number() && !at_phase(q[6].get<double>())) continue;
      if (a.geometry.project(Eigen::Vector3d(q[1].get<double>(), q[2].get<double>(), q[3].get<double>()), &cr))
        points += fmt::format("{:.1f},{:.1f} ", cr.x(), cr.y());
    }
    if (!points.empty()) s += fmt::format(R"(<polyline class="pathref" points="{}"/>)", points);
  }
  return s + "</svg>\n" +
         fmt::format(
             "<p class=small>The frame at {:.1f} s of the session ({} branches holding contrast), as the beam "
             "showed it, and the tip projected by that frame's geometry: faint, every state (the heart carries "
             "the tip to and fro); joined, the states at the frame's phase of the heart{} (green on the route to "
             "the target, red off it){}.</p>\n",
             a.time_s, a.contrast_branches,
             beating ? fmt::format(" ({:.2f}, within {:.2f} of a beat)", a.heart_phase, kPhaseWindow) : std::string(),
             reference ? "; dashed, the reference run's" : "");
}

}  // namespace

std::string debrief_html(const DebriefFigures& f, const nlohmann::json* reference, const std::string& title) {
  const nlohmann::json trainee = to_json(f);
  std::string s = R"(<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>)" +
                  escape(title) + R"(</title>
<style>
body { font-family: sans-serif; margin: 24px; color: #222; max-width: 980px; }
h1 { font-size: 22px; } h2 { font-size: 17px; margin-top: 28px; }
table { border-collapse: collapse; } td, th { border-bottom: 1px solid #ddd; padding: 4px 10px; text-align: left; }
td.n { text-align: right; font-variant-numeric: tabular-nums; } td.src, .small { color: #777; font-size: 12px; }
.lab { font-size: 13px; fill: #333; } .grid { stroke: #ccc; stroke-width: 1; } .risk { stroke: #d33; stroke-dasharray: 6 4; }
.fluoro { fill: #4a90d9; } .cine { fill: #e08a1e; } .contrast { fill: #7b4fd0; } .carm { stroke: #333; stroke-width: 2; }
.off { fill: #d33; } .prolapse { fill: #b10dc9; } .buckle { fill: #ff851b; } .force { fill: #d33; fill-opacity: 0.7; } .forceline { fill: none; stroke: #333; stroke-width: 1.2; }
.pathon { fill: none; stroke: #2ecc40; stroke-width: 2.5; } .pathoff { fill: none; stroke: #ff4136; stroke-width: 2.5; }
.pathall { fill: none; stroke: #2ecc40; stroke-opacity: 0.25; stroke-width: 1; }
.pathref { fill: none; stroke: #39cccc; stroke-width: 2; stroke-dasharray: 6 4; }
svg text.small { fill: #555; font-size: 11px; }
</style></head><body>
)";
  s += "<h1>" + escape(title) + "</h1>\n";
  s += fmt::format(
      "<p>Target branch: <b>{}</b>. Figures from the simulation's own truth; definitions and sources in "
      "docs/debrief.md.{}</p>\n",
      f.target_branch.empty() ? std::string("none") : escape(f.target_branch),
      reference ? " The reference column is another session's debrief." : "");
  s += "<h2>Figures</h2>\n" + figures_table(trainee, reference);
  s += "<h2>Timeline</h2>\n" + timeline_svg(f);
  s += "<h2>The tip's path</h2>\n" + angiogram_svg(f, reference);
  s += "<h2>Tip force on the wall</h2>\n";
  s += f.tip_forces_known ? force_svg(f)
                          : std::string(
                                "<p>Not computed: the chain-mail wire has no load response (the rod wire, "
                                "<code>guidewire.model \"rod\"</code>, computes the wall's force).</p>\n");
  s += fmt::format("<p class=small>{} wire states; {} timeline entries{}.</p>\n", f.wire_states, f.timeline.size(),
                   f.timeline_dropped ? fmt::format(" ({} more not listed)", f.timeline_dropped) : std::string());
  return s + "</body></html>\n";
}

}  // namespace pcisim::server
