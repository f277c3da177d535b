#include "modeling/cta/coronary_labels.h"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include "realtime/percentile.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

double polyline_length(const std::vector<Vector3d>& p, size_t from = 0) {
  double s = 0;
  for (size_t i = from + 1; i < p.size(); ++i) s += (p[i] - p[i - 1]).norm();
  return s;
}

// each branch's own length plus that of everything hanging from it
std::vector<double> subtree_lengths(const std::vector<ModelBranch>& b) {
  std::vector<double> len(b.size());
  for (size_t i = 0; i < b.size(); ++i) len[i] = polyline_length(b[i].points_mm);
  for (size_t i = b.size(); i-- > 0;) {
    if (b[i].parent >= 0) len[b[i].parent] += len[i];
  }
  return len;
}

// branch 0 cut at point `at` into two: 0 keeps [0, at], a new last branch holds [at, end] and the
// children that left from there
std::vector<ModelBranch> split_first(std::vector<ModelBranch> b, int at, int* tail_index) {
  ModelBranch tail;
  tail.points_mm.assign(b[0].points_mm.begin() + at, b[0].points_mm.end());
  tail.radius_mm.assign(b[0].radius_mm.begin() + at, b[0].radius_mm.end());
  tail.parent = 0;
  tail.parent_point = at;
  b[0].points_mm.resize(at + 1);
  b[0].radius_mm.resize(at + 1);
  const int t = static_cast<int>(b.size());
  for (auto& c : b) {
    if (c.parent == 0 && c.parent_point > at) {
      c.parent = t;
      c.parent_point -= at;
    }
  }
  b.push_back(std::move(tail));
  *tail_index = t;
  return b;
}

// the direction of a polyline from point `from` over `count` points (clamped), normalised
Vector3d direction(const std::vector<Vector3d>& p, int from, int count) {
  const int a = std::clamp(from, 0, int(p.size()) - 1), b = std::clamp(from + count, 0, int(p.size()) - 1);
  const Vector3d d = p[std::max(a, b)] - p[std::min(a, b)];
  return d.norm() > 0 ? d.normalized() : Vector3d::UnitX();
}

// the tracing continues each vessel into whichever branch reaches farthest; a vessel continues
// where it runs on straightest: at every major branch point, when a child leaves more in line with
// the incoming vessel than the vessel's own continuation (by more than the margin), the two
// swap: the child becomes the continuation and the old continuation a side branch
void prefer_straight_continuations(std::vector<ModelBranch>& b, double major_mm, double margin_deg, int look) {
  const double margin = margin_deg * 3.14159265358979 / 180.0;
  for (size_t i = 0; i < b.size(); ++i) {
    for (int j = look; j + look < int(b[i].points_mm.size()); ++j) {
      const std::vector<double> sub = subtree_lengths(b);
      for (size_t c = 0; c < b.size(); ++c) {
        if (b[c].parent != int(i) || b[c].parent_point != j || sub[c] < major_mm) continue;
        const Vector3d in = direction(b[i].points_mm, j - look, look);
        const double own = std::acos(std::clamp(in.dot(direction(b[i].points_mm, j, look)), -1.0, 1.0));
        const double side = std::acos(std::clamp(in.dot(direction(b[c].points_mm, 0, look)), -1.0, 1.0));
        if (side + margin >= own) continue;
        // swap the tail of i after j with branch c
        ModelBranch tail;
        tail.points_mm.assign(b[i].points_mm.begin() + j, b[i].points_mm.end());
        tail.radius_mm.assign(b[i].radius_mm.begin() + j, b[i].radius_mm.end());
        tail.parent = int(i);
        tail.parent_point = j;
        b[i].points_mm.resize(j + 1);
        b[i].radius_mm.resize(j + 1);
        b[i].points_mm.insert(b[i].points_mm.end(), b[c].points_mm.begin() + 1, b[c].points_mm.end());
        b[i].radius_mm.insert(b[i].radius_mm.end(), b[c].radius_mm.begin() + 1, b[c].radius_mm.end());
        for (size_t g = 0; g < b.size(); ++g) {
          if (g == c) continue;
          if (b[g].parent == int(i) && b[g].parent_point > j) {
            b[g].parent = int(c);
            b[g].parent_point -= j;
          } else if (b[g].parent == int(c)) {
            b[g].parent = int(i);
            b[g].parent_point += j;
          }
        }
        b[c] = std::move(tail);
        break;
      }
    }
  }
}

double mean_y_first(const ModelBranch& b, double mm) {
  double s = 0, y = 0;
  int n = 0;
  for (size_t i = 0; i < b.points_mm.size() && s <= mm; ++i) {
    if (i > 0) s += (b.points_mm[i] - b.points_mm[i - 1]).norm();
    y += b.points_mm[i].y();
    ++n;
  }
  return n ? y / n : 0.0;
}

}  // namespace

anatomy::VesselTree label_coronary_trees(const std::vector<anatomy::CenterlinePoint>& aorta_mm,
                                         const std::vector<ModelTree>& trees, const LabelOptions& o) {
  anatomy::VesselTree out;
  anatomy::VesselBranch aorta{"aorta", -1, -1, {}};
  for (const auto& p : aorta_mm) aorta.points.push_back({p.position_m * 1e-3, p.radius_m * 1e-3});
  out.branches.push_back(std::move(aorta));
  const std::vector<anatomy::CenterlinePoint> ap = out.branches[0].points;  // a copy: the list grows
  auto nearest_aorta_point = [&](const Vector3d& p_mm) {
    int best = 0;
    for (size_t i = 0; i < ap.size(); ++i) {
      if ((ap[i].position_m * 1e3 - p_mm).norm() < (ap[best].position_m * 1e3 - p_mm).norm()) best = int(i);
    }
    return best;
  };

  bool have_left = false, have_right = false;
  int generic = 3;
  for (const ModelTree& tree : trees) {
    if (tree.branches.empty()) continue;
    std::vector<ModelBranch> b = tree.branches;
    // the vessel's own line carried back through the aortic wall to the aortic centerline point it
    // passes closest to: in front of the first branch
    // the samples next to the aorta: their path bends into the ostium's funnel and their
    // cross-sections see the aortic lumen; they are dropped (no child leaves there) and replaced
    // by the vessel's line and radius from beyond
    const double aortic_r_near = ap[nearest_aorta_point(tree.aortic_centre_mm)].radius_m * 1e3;
    size_t first_clear = 0;
    while (first_clear + 2 < b[0].points_mm.size() &&
           (b[0].points_mm[first_clear] - tree.aortic_centre_mm).norm() < aortic_r_near + o.ostium_clearance_mm) {
      ++first_clear;
    }
    for (const auto& c : b) {
      if (c.parent == 0) first_clear = std::min<size_t>(first_clear, std::max(0, c.parent_point - 1));
    }
    std::vector<double> beyond(b[0].radius_mm.begin() + first_clear,
                               b[0].radius_mm.begin() + std::min(b[0].radius_mm.size(), first_clear + 10));
    double r_ostium = b[0].radius_mm[first_clear];
    if (!beyond.empty()) r_ostium = realtime::upper_median_in_place(std::span<double>(beyond));
    b[0].points_mm.erase(b[0].points_mm.begin(), b[0].points_mm.begin() + first_clear);
    b[0].radius_mm.erase(b[0].radius_mm.begin(), b[0].radius_mm.begin() + first_clear);
    for (auto& c : b) {
      if (c.parent == 0) c.parent_point -= static_cast<int>(first_clear);
    }
    // the vessel's own line, carried back: it enters the aorta where it passes closest to the
    // aortic centerline (the aorta's ridge is flat along its axis, so "the centre beside the
    // ostium" alone could lie anywhere along the root)
    const Vector3d p0 = b[0].points_mm.front();
    int span = 1;
    for (double arc = 0; span + 1 < int(b[0].points_mm.size()) && arc < o.ostium_direction_mm; ++span) {
      arc += (b[0].points_mm[span] - b[0].points_mm[span - 1]).norm();
    }
    const Vector3d d0 = direction(b[0].points_mm, 0, span);
    int on_aorta = 0;
    double best_gap = 1e300;
    for (size_t i = 0; i < ap.size(); ++i) {
      const Vector3d a = ap[i].position_m * 1e3;
      const double t = std::max(0.0, (p0 - a).dot(d0));  // back along the line from p0
      const double gap_mm = (p0 - t * d0 - a).norm();
      if (gap_mm < best_gap) {
        best_gap = gap_mm;
        on_aorta = static_cast<int>(i);
      }
    }
    // one straight line from that centerline point to the vessel: a kink at the centre (from the
    // centerline point across to the vessel's line, ~2 mm at right angles) would be the first
    // segment, the direction the guide catheter engages along (anatomy guide_catheter_path): the
    // wire would leave it 76 degrees off the ostium (phantom 1's model)
    const Vector3d start = ap[on_aorta].position_m * 1e3;
    std::vector<Vector3d> lead;
    auto walk = [&](const Vector3d& a, const Vector3d& c) {
      const int n = static_cast<int>((c - a).norm() / o.point_spacing_mm);
      for (int i = 0; i < n; ++i) lead.push_back(a + (c - a) * (double(i) / n));
    };
    walk(start, p0);
    const int extra = static_cast<int>(lead.size());
    if (extra > 0) {
      b[0].points_mm.insert(b[0].points_mm.begin(), lead.begin(), lead.end());
      b[0].radius_mm.insert(b[0].radius_mm.begin(), extra, r_ostium);
      for (auto& c : b) {
        if (c.parent == 0) c.parent_point += extra;
      }
    }

    prefer_straight_continuations(b, o.major_branch_mm, o.straighter_by_deg, o.direction_points);

    // which tree, and its names
    const bool left = (tree.ostium_mm - tree.aortic_centre_mm).x() > 0;
    std::vector<std::string> name(b.size());
    if (left && !have_left) {
      have_left = true;
      // the first major branch point within the LM's reach
      const std::vector<double> sub = subtree_lengths(b);
      int split = -1;
      double arc = 0;
      for (size_t i = 1; i < b[0].points_mm.size() && arc <= o.lm_max_length_mm + extra * o.point_spacing_mm; ++i) {
        arc += (b[0].points_mm[i] - b[0].points_mm[i - 1]).norm();
        for (size_t c = 1; c < b.size(); ++c) {
          if (b[c].parent == 0 && b[c].parent_point == int(i) && sub[c] >= o.major_branch_mm) split = int(i);
        }
        if (split >= 0) break;
      }
      if (split < 0) {
        name.assign(b.size(), "");
        name[0] = "LCA";
      } else {
        int tail = -1;
        b = split_first(std::move(b), split, &tail);
        name.assign(b.size(), "");
        name[0] = "LM";
        // the other continuation: the major child at the split
        int other = -1;
        const std::vector<double> sub2 = subtree_lengths(b);
        for (size_t c = 1; c < b.size(); ++c) {
          if (int(c) != tail && b[c].parent == 0 && b[c].parent_point == split &&
              (other < 0 || sub2[c] > sub2[other])) {
            other = int(c);
          }
        }
        const bool tail_anterior = other < 0 || mean_y_first(b[tail], 15) <= mean_y_first(b[other], 15);
        name[tail] = tail_anterior ? "LAD" : "LCx";
        if (other >= 0) name[other] = tail_anterior ? "LCx" : "LAD";
      }
    } else if (!left && !have_right) {
      have_right = true;
      name.assign(b.size(), "");
      name[0] = "RCA";
    } else {
      name.assign(b.size(), "");
      name[0] = fmt::format("CA{}", generic++);
    }
    // side branches, proximal first: diagonals on the LAD, marginals on the LCx, else by parent
    std::vector<int> order(b.size());
    for (size_t i = 0; i < b.size(); ++i) order[i] = int(i);
    std::function<void(int)> name_children = [&](int p) {
      std::vector<int> kids;
      for (size_t c = 0; c < b.size(); ++c) {
        if (b[c].parent == p && name[c].empty()) kids.push_back(int(c));
      }
      std::sort(kids.begin(), kids.end(), [&](int a, int c) { return b[a].parent_point < b[c].parent_point; });
      int k = 1;
      for (int c : kids) {
        if (name[p] == "LAD") {
          name[c] = fmt::format("D{}", k++);
        } else if (name[p] == "LCx") {
          name[c] = fmt::format("OM{}", k++);
        } else {
          name[c] = fmt::format("{}-{}", name[p], k++);
        }
      }
      for (size_t c = 0; c < b.size(); ++c) {
        if (b[c].parent == p) name_children(int(c));
      }
    };
    name_children(0);

    // into the tree, parents first (breadth first from the first branch)
    std::vector<int> index_of(b.size(), -1);
    std::vector<int> queue{0};
    for (size_t q = 0; q < queue.size(); ++q) {
      const int i = queue[q];
      anatomy::VesselBranch vb;
      vb.name = name[i];
      if (i == 0) {
        vb.parent = 0;
        vb.parent_point = on_aorta;
      } else {
        vb.parent = index_of[b[i].parent];
        vb.parent_point = std::min<int>(b[i].parent_point, int(b[b[i].parent].points_mm.size()) - 1);
      }
      for (size_t k = 0; k < b[i].points_mm.size(); ++k) {
        vb.points.push_back({b[i].points_mm[k] * 1e-3, b[i].radius_mm[k] * 1e-3});
      }
      // a child starts exactly on its parent's point
      if (i != 0 && !vb.points.empty()) {
        vb.points.front().position_m = out.branches[vb.parent].points[vb.parent_point].position_m;
      } else if (!vb.points.empty()) {
        vb.points.front().position_m = ap[on_aorta].position_m;
      }
      index_of[i] = static_cast<int>(out.branches.size());
      out.branches.push_back(std::move(vb));
      for (size_t c = 0; c < b.size(); ++c) {
        if (b[c].parent == i) queue.push_back(int(c));
      }
    }
  }
  return out;
}

}  // namespace pcisim::modeling
