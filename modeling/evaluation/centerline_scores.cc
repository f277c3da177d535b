#include "modeling/evaluation/centerline_scores.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "modeling/evaluation/closest_point_bvh.h"
#include "realtime/percentile.h"

namespace pcisim::modeling {

using anatomy::VesselTree;
using Eigen::Vector3d;

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kArcSlackM = 1e-9;  // arc comparisons: a point at a cut belongs to both sides

// a branch's centerline as scored: its points, after the parent's point it leaves from when that
// point is not already its first
struct Polyline {
  int vertex_offset = 0;  // 1 when the parent's point was put in front
  std::vector<Vector3d> p;
  std::vector<double> r, arc;
  double length_m() const { return arc.empty() ? 0.0 : arc.back(); }
};

struct Sample {
  Vector3d p;
  double r = 0, arc_m = 0;
};

// where a point's nearest centerline point lies
struct Location {
  double distance_m = kInf;
  int branch = -1;
  double arc_m = 0, radius_m = 0;
};

bool is_excluded(const std::string& name, const std::vector<std::string>& exclude) {
  return std::find(exclude.begin(), exclude.end(), name) != exclude.end();
}

std::vector<bool> included_branches(const VesselTree& tree, const std::vector<std::string>& exclude) {
  std::vector<bool> in(tree.branches.size());
  for (size_t b = 0; b < in.size(); ++b) {
    in[b] = !tree.branches[b].points.empty() && !is_excluded(tree.branches[b].name, exclude);
  }
  return in;
}

// the polyline of every included branch (empty for the others)
std::vector<Polyline> polylines(const VesselTree& tree, const std::vector<bool>& in) {
  std::vector<Polyline> lines(tree.branches.size());
  for (size_t b = 0; b < lines.size(); ++b) {
    if (!in[b]) continue;
    const auto& br = tree.branches[b];
    Polyline& pl = lines[b];
    const bool has_parent = br.parent >= 0 && br.parent < static_cast<int>(in.size()) && in[br.parent];
    if (has_parent) {
      const auto& pp = tree.branches[br.parent].points;
      if (br.parent_point >= 0 && br.parent_point < static_cast<int>(pp.size()) &&
          (pp[br.parent_point].position_m - br.points[0].position_m).norm() > kArcSlackM) {
        pl.p.push_back(pp[br.parent_point].position_m);
        pl.r.push_back(pp[br.parent_point].radius_m);
        pl.vertex_offset = 1;
      }
    }
    for (const auto& q : br.points) {
      pl.p.push_back(q.position_m);
      pl.r.push_back(q.radius_m);
    }
    pl.arc.resize(pl.p.size());
    pl.arc[0] = 0;
    for (size_t i = 1; i < pl.p.size(); ++i) pl.arc[i] = pl.arc[i - 1] + (pl.p[i] - pl.p[i - 1]).norm();
  }
  return lines;
}

// points at equal arc-length steps of at most spacing_m over [0, end_m], radii interpolated
void sample(const Polyline& pl, double end_m, double spacing_m, std::vector<Sample>* out) {
  end_m = std::clamp(end_m, 0.0, pl.length_m());
  const int n = end_m > 0 ? std::max(1, static_cast<int>(std::ceil(end_m / spacing_m - 1e-9))) : 0;
  size_t seg = 0;
  for (int k = 0; k <= n; ++k) {
    const double s = n > 0 ? end_m * k / n : 0.0;
    while (seg + 2 < pl.p.size() && pl.arc[seg + 1] < s) ++seg;
    if (pl.p.size() == 1) {
      out->push_back({pl.p[0], pl.r[0], 0.0});
      continue;
    }
    const double len = pl.arc[seg + 1] - pl.arc[seg];
    const double t = len > 0 ? std::clamp((s - pl.arc[seg]) / len, 0.0, 1.0) : 0.0;
    out->push_back({pl.p[seg] + t * (pl.p[seg + 1] - pl.p[seg]), pl.r[seg] + t * (pl.r[seg + 1] - pl.r[seg]), s});
  }
}

// every segment of a tree's polylines, for nearest-point queries
class Centerlines {
 public:
  explicit Centerlines(const std::vector<Polyline>& lines) : lines_(lines), set_(build(lines)) {}
  // the nearest point of any branch. Ties (a branch's first point lies on its parent) go to the
  // radius nearest prefer_radius_m when given, then to the lower branch index.
  Location nearest(const Vector3d& p, double prefer_radius_m = kNan) const {
    const SegmentSet::Hit first = set_.nearest(p);
    Location best;
    if (first.segment < 0) return best;
    set_.visit_within(p, first.distance_m + kTieM, [&](const SegmentSet::Hit& hit) {
      const Location loc = locate(hit);
      if (best.branch < 0) {
        best = loc;
        return;
      }
      const double e = std::abs(loc.radius_m - prefer_radius_m), e_best = std::abs(best.radius_m - prefer_radius_m);
      const bool better = std::isnan(prefer_radius_m) || e == e_best
                              ? loc.branch < best.branch || (loc.branch == best.branch && loc.arc_m < best.arc_m)
                              : e < e_best;
      if (better) best = loc;
    });
    best.distance_m = std::min(best.distance_m, first.distance_m);
    return best;
  }

 private:
  static constexpr double kTieM = 1e-9;
  Location locate(const SegmentSet::Hit& hit) const {
    const auto [b, i] = seg_[hit.segment];
    const Polyline& pl = lines_[b];
    const int j = std::min(i + 1, static_cast<int>(pl.p.size()) - 1);
    Location loc;
    loc.distance_m = hit.distance_m;
    loc.branch = b;
    loc.arc_m = pl.arc[i] + hit.t * (pl.arc[j] - pl.arc[i]);
    loc.radius_m = pl.r[i] + hit.t * (pl.r[j] - pl.r[i]);
    return loc;
  }
  SegmentSet build(const std::vector<Polyline>& lines) {
    std::vector<Vector3d> a, b;
    for (size_t k = 0; k < lines.size(); ++k) {
      const auto& pl = lines[k];
      // a branch of one point is a segment of no length
      for (size_t i = 0; i + 1 < std::max<size_t>(pl.p.size(), 2) && !pl.p.empty(); ++i) {
        a.push_back(pl.p[i]);
        b.push_back(pl.p[std::min(i + 1, pl.p.size() - 1)]);
        seg_.push_back({static_cast<int>(k), static_cast<int>(i)});
      }
    }
    return SegmentSet(std::move(a), std::move(b));
  }
  const std::vector<Polyline>& lines_;
  std::vector<std::pair<int, int>> seg_;  // (branch, first vertex) per segment
  SegmentSet set_;
};

// one branch of a vessel's path: [0, end_m] of its polyline, at offset_m from the ostium
struct PathPart {
  int branch;
  double offset_m, end_m;
};

struct Vessel {
  std::string name;
  std::vector<PathPart> parts;  // ostium first
  double length_m = 0;
  double ot_end_m = -kInf;  // the most distal vertex wide enough for OT; -inf when none is
};

// every path from an ostium to a branch end that no child continues
std::vector<Vessel> vessels(const VesselTree& tree, const std::vector<bool>& in, const std::vector<Polyline>& lines,
                            double min_diameter_m) {
  const int nb = static_cast<int>(tree.branches.size());
  auto parent_of = [&](int b) {
    const int p = tree.branches[b].parent;
    return p >= 0 && p < nb && in[p] ? p : -1;
  };
  std::vector<bool> continued(nb, false);
  for (int b = 0; b < nb; ++b) {
    const int p = parent_of(b);
    if (in[b] && p >= 0 && tree.branches[b].parent_point == static_cast<int>(tree.branches[p].points.size()) - 1) {
      continued[p] = true;
    }
  }
  std::vector<Vessel> out;
  for (int leaf = 0; leaf < nb; ++leaf) {
    if (!in[leaf] || continued[leaf]) continue;
    std::vector<int> chain;
    for (int b = leaf; b >= 0; b = parent_of(b)) {
      chain.push_back(b);
      if (chain.size() > static_cast<size_t>(nb)) throw std::invalid_argument("vessel tree: a cycle of parents");
    }
    std::reverse(chain.begin(), chain.end());
    Vessel v;
    v.name = tree.branches[leaf].name;
    double offset = 0;
    for (size_t k = 0; k < chain.size(); ++k) {
      const Polyline& pl = lines[chain[k]];
      double end = pl.length_m();
      if (k + 1 < chain.size()) {
        const int pp = tree.branches[chain[k + 1]].parent_point;
        if (pp >= 0 && pp + pl.vertex_offset < static_cast<int>(pl.p.size())) end = pl.arc[pp + pl.vertex_offset];
      }
      v.parts.push_back({chain[k], offset, end});
      for (size_t i = 0; i < pl.p.size() && pl.arc[i] <= end + kArcSlackM; ++i) {
        if (2 * pl.r[i] >= min_diameter_m) v.ot_end_m = std::max(v.ot_end_m, offset + pl.arc[i]);
      }
      offset += end;
    }
    v.length_m = offset;
    out.push_back(std::move(v));
  }
  return out;
}

// running counts of one score
struct Tally {
  int tpr = 0, fn = 0, tpm = 0, fp = 0;
  int ot_tp = 0, ot_all = 0;
  double ai_sum_m = 0;
  void reference(bool tp, double d_m, bool in_ot) {
    (tp ? tpr : fn)++;
    if (tp) ai_sum_m += d_m;
    if (in_ot) ot_tp += tp, ot_all++;
  }
  void extracted(bool tp, double d_m, bool in_ot) {
    (tp ? tpm : fp)++;
    if (tp) ai_sum_m += d_m;
    if (in_ot) ot_tp += tp, ot_all++;
  }
  double ov() const { return ratio(tpr + tpm, tpr + tpm + fn + fp); }
  double ot() const { return ratio(ot_tp, ot_all); }
  double ai_mm() const { return tpr + tpm > 0 ? 1e3 * ai_sum_m / (tpr + tpm) : kNan; }
  static double ratio(int a, int b) { return b > 0 ? static_cast<double>(a) / b : kNan; }
};

// an extracted point scored against the reference
struct ExtractedPoint {
  Location at;
  bool tp = false;
};

}  // namespace

CenterlineScores score_centerlines(const VesselTree& reference, const VesselTree& extracted,
                                   const CenterlineScoreOptions& options) {
  if (!(options.sample_spacing_m > 0)) throw std::invalid_argument("score_centerlines: sample_spacing_m must be > 0");
  const double h = options.sample_spacing_m;
  const std::vector<bool> ref_in = included_branches(reference, options.exclude);
  const std::vector<bool> ext_in = included_branches(extracted, options.exclude);
  const std::vector<Polyline> ref_lines = polylines(reference, ref_in);
  const std::vector<Polyline> ext_lines = polylines(extracted, ext_in);
  const Centerlines ref_set(ref_lines), ext_set(ext_lines);
  const std::vector<Vessel> ves = vessels(reference, ref_in, ref_lines, options.min_diameter_ot_m);

  // each branch's part within OT: the farthest any vessel through it keeps
  std::vector<double> ot_end(reference.branches.size(), -kInf);
  for (const Vessel& v : ves) {
    for (const PathPart& part : v.parts) {
      const double local = v.ot_end_m - part.offset_m;
      if (local >= -kArcSlackM) ot_end[part.branch] = std::max(ot_end[part.branch], std::min(local, part.end_m));
    }
  }

  CenterlineScores out;
  Tally all;
  std::vector<double> radius_err_mm;
  std::vector<Sample> samples;
  // reference points, each branch once
  for (size_t b = 0; b < ref_lines.size(); ++b) {
    if (!ref_in[b]) continue;
    samples.clear();
    sample(ref_lines[b], ref_lines[b].length_m(), h, &samples);
    for (const Sample& s : samples) {
      const Location at = ext_set.nearest(s.p, s.r);
      const bool tp = at.distance_m <= s.r;
      all.reference(tp, at.distance_m, s.arc_m <= ot_end[b] + kArcSlackM);
      if (tp) radius_err_mm.push_back(1e3 * std::abs(at.radius_m - s.r));
    }
  }
  // extracted points against the reference radius at their nearest reference point
  std::vector<ExtractedPoint> ext_points;
  for (size_t b = 0; b < ext_lines.size(); ++b) {
    if (!ext_in[b]) continue;
    samples.clear();
    sample(ext_lines[b], ext_lines[b].length_m(), h, &samples);
    for (const Sample& s : samples) {
      ExtractedPoint e;
      e.at = ref_set.nearest(s.p);
      e.tp = e.at.distance_m <= e.at.radius_m;
      all.extracted(e.tp, e.at.distance_m, e.at.branch >= 0 && e.at.arc_m <= ot_end[e.at.branch] + kArcSlackM);
      ext_points.push_back(e);
    }
  }
  out.ov = all.ov();
  out.ot = all.ot();
  out.ai_mm = all.ai_mm();
  out.tp_reference = all.tpr;
  out.fn = all.fn;
  out.tp_extracted = all.tpm;
  out.fp = all.fp;
  double sum = 0;
  for (double e : radius_err_mm) sum += e;
  out.radius_error_mean_mm = radius_err_mm.empty() ? kNan : sum / radius_err_mm.size();
  out.radius_error_p95_mm = realtime::percentile(std::move(radius_err_mm), 0.95);

  // per vessel: its path's points from the ostium, and the extracted points nearest to it
  double of_sum = 0;
  for (const Vessel& v : ves) {
    VesselScores vs;
    vs.name = v.name;
    vs.length_mm = 1e3 * v.length_m;
    vs.ot_length_mm = v.ot_end_m > -kInf ? 1e3 * v.ot_end_m : 0.0;
    vs.first_fn_mm = kNan;
    Tally t;
    int before_first_fn = 0, points = 0;
    for (size_t k = 0; k < v.parts.size(); ++k) {
      const PathPart& part = v.parts[k];
      samples.clear();
      sample(ref_lines[part.branch], part.end_m, h, &samples);
      // a branch's first point is its parent's last point of the path
      for (size_t i = k > 0 ? 1 : 0; i < samples.size(); ++i) {
        const Sample& s = samples[i];
        const double arc = part.offset_m + s.arc_m;
        const Location at = ext_set.nearest(s.p);
        const bool tp = at.distance_m <= s.r;
        t.reference(tp, at.distance_m, arc <= v.ot_end_m + kArcSlackM);
        if (!tp && std::isnan(vs.first_fn_mm)) vs.first_fn_mm = 1e3 * arc;
        if (std::isnan(vs.first_fn_mm)) ++before_first_fn;
        ++points;
      }
    }
    for (const ExtractedPoint& e : ext_points) {
      for (const PathPart& part : v.parts) {
        if (part.branch != e.at.branch || e.at.arc_m > part.end_m + kArcSlackM) continue;
        t.extracted(e.tp, e.at.distance_m, part.offset_m + e.at.arc_m <= v.ot_end_m + kArcSlackM);
        break;
      }
    }
    vs.ov = t.ov();
    vs.ot = t.ot();
    vs.ai_mm = t.ai_mm();
    vs.of = Tally::ratio(before_first_fn, points);
    vs.tp_reference = t.tpr;
    vs.fn = t.fn;
    vs.tp_extracted = t.tpm;
    vs.fp = t.fp;
    of_sum += vs.of;
    out.vessels.push_back(std::move(vs));
  }
  out.of = ves.empty() ? kNan : of_sum / ves.size();
  return out;
}

VesselTree outside_aorta(const VesselTree& tree, const VesselTree& truth) {
  const int a = truth.find("aorta");
  if (a < 0) return tree;
  const auto& aorta = truth.branches[a];
  auto inside = [&](const Vector3d& p) {
    for (size_t i = 0; i + 1 < aorta.points.size(); ++i) {
      const Vector3d x = aorta.points[i].position_m, ab = aorta.points[i + 1].position_m - x;
      const double t = std::clamp((p - x).dot(ab) / std::max(ab.squaredNorm(), 1e-18), 0.0, 1.0);
      const double r = aorta.points[i].radius_m + t * (aorta.points[i + 1].radius_m - aorta.points[i].radius_m);
      if ((x + t * ab - p).norm() < r) return true;
    }
    return false;
  };
  VesselTree out = tree;
  for (auto& b : out.branches) {
    if (b.name == "aorta" || b.parent < 0 || tree.branches[b.parent].name != "aorta") continue;
    // a tree's first branch: drop its leading points inside the aorta; its children's junction
    // indices move with it
    size_t cut = 0;
    while (cut + 2 < b.points.size() && inside(b.points[cut].position_m)) ++cut;
    if (cut == 0) continue;
    const int self = static_cast<int>(&b - out.branches.data());
    b.points.erase(b.points.begin(), b.points.begin() + cut);
    for (auto& c : out.branches) {
      if (c.parent == self) c.parent_point = std::max(0, c.parent_point - static_cast<int>(cut));
    }
  }
  return out;
}

}  // namespace pcisim::modeling
