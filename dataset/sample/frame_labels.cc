#include "dataset/sample/frame_labels.h"

#include <algorithm>
#include <cmath>

namespace pcisim::dataset {
namespace {

// positions to a micrometre and a thousandth of a pixel: a frame's labels stay a few tens of kB
double r3(double x) {
  return std::round(x * 1e3) / 1e3;
}

nlohmann::json v3(const Eigen::Vector3d& p) {
  return {r3(p.x()), r3(p.y()), r3(p.z())};
}

// the projection's own vectors, exact: the formula the labels document must reproduce them
nlohmann::json exact(const Eigen::Vector3d& p) {
  return {p.x(), p.y(), p.z()};
}

// a pixel position, null when the point is not in front of the source
nlohmann::json px(const Eigen::Vector2d& p) {
  if (!p.allFinite()) return nullptr;
  return {r3(p.x()), r3(p.y())};
}

}  // namespace

// the ray from the source s through x meets the detector plane (normal n, at distance
// d = n.(centre - s)) at s + (d / w)(x - s), w = n.(x - s); its column is
// u.(hit - centre) / pitch + (W - 1) / 2, linear in x after multiplying by w
Eigen::Matrix<double, 3, 4> projection_matrix(const xray::DetectorGeometry& g) {
  const Eigen::Vector3d n = g.normal();
  const Eigen::Vector3d& s = g.source_mm;
  const double d = n.dot(g.center_mm - s);
  Eigen::Matrix<double, 1, 4> row_w, row_u, row_v;
  row_w << n.transpose(), -n.dot(s);
  row_u << g.u.transpose(), -g.u.dot(s);
  row_v << g.v.transpose(), -g.v.dot(s);
  const double kc = g.u.dot(s - g.center_mm) / g.pixel_mm + 0.5 * (g.width - 1);
  const double kr = g.v.dot(s - g.center_mm) / g.pixel_mm + 0.5 * (g.height - 1);
  Eigen::Matrix<double, 3, 4> p;
  p.row(0) = (d / g.pixel_mm) * row_u + kc * row_w;
  p.row(1) = (d / g.pixel_mm) * row_v + kr * row_w;
  p.row(2) = row_w;
  return p;
}

std::vector<Eigen::Vector3d> wire_keypoints(const xray::DetectorGeometry& g, std::span<const Eigen::Vector3d> wire_mm,
                                            int count, double span_mm) {
  std::vector<Eigen::Vector3d> out;
  if (wire_mm.empty() || count < 2) return out;
  // arc length from the tip back along the wire, node by node
  std::vector<double> from_tip(wire_mm.size(), 0.0);
  for (size_t k = wire_mm.size() - 1; k-- > 0;) from_tip[k] = from_tip[k + 1] + (wire_mm[k + 1] - wire_mm[k]).norm();
  const double span = std::min(span_mm, from_tip[0]);
  size_t seg = 0;  // the segment [seg, seg + 1] holding the current distance
  for (int i = 0; i < count; ++i) {
    const double s = span * (1.0 - static_cast<double>(i) / (count - 1));  // distance from the tip
    while (seg + 1 < wire_mm.size() - 1 && from_tip[seg + 1] > s) ++seg;
    Eigen::Vector3d p = wire_mm.back();
    if (wire_mm.size() > 1) {
      const double len = from_tip[seg] - from_tip[seg + 1];
      const double t = len > 0 ? (from_tip[seg] - s) / len : 0.0;
      p = wire_mm[seg] + std::clamp(t, 0.0, 1.0) * (wire_mm[seg + 1] - wire_mm[seg]);
    }
    Eigen::Vector2d cr;
    const bool front = g.project(p, &cr);
    const bool inside = front && cr.allFinite() && cr.x() >= -0.5 && cr.x() < g.width - 0.5 && cr.y() >= -0.5 &&
                        cr.y() < g.height - 0.5;
    out.emplace_back(front ? cr.x() : NAN, front ? cr.y() : NAN, inside ? 2.0 : 0.0);
  }
  return out;
}

nlohmann::json frame_labels(const FrameTruth& t) {
  const auto& g = t.geometry;
  const Eigen::Matrix<double, 3, 4> p = projection_matrix(g);
  nlohmann::json matrix = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) matrix.push_back({p(r, 0), p(r, 1), p(r, 2), p(r, 3)});

  nlohmann::json wire_mm = nlohmann::json::array(), wire_px = nlohmann::json::array(), keys = nlohmann::json::array();
  for (const auto& w : t.wire_mm) wire_mm.push_back(v3(w));
  for (const auto& w : t.wire_px) wire_px.push_back(px(w));
  for (const auto& k : t.keypoints)
    keys.push_back({std::isfinite(k.x()) ? nlohmann::json(r3(k.x())) : nlohmann::json(),
                    std::isfinite(k.y()) ? nlohmann::json(r3(k.y())) : nlohmann::json(), static_cast<int>(k.z())});

  // every branch's centerline, where the heart has carried it, and its projection
  nlohmann::json vessels = nlohmann::json::array();
  if (t.tree) {
    size_t flat = 0;
    const bool moved = !t.vessel_points_mm.empty();
    for (size_t b = 0; b < t.tree->branches.size(); ++b) {
      const auto& br = t.tree->branches[b];
      nlohmann::json pts = nlohmann::json::array(), pix = nlohmann::json::array(), ops = nlohmann::json::array();
      for (const auto& cp : br.points) {
        ops.push_back(flat < t.point_opacity.size() ? std::round(t.point_opacity[flat] * 1e3) / 1e3 : 0.0);
        const Eigen::Vector3d x =
            moved && flat < t.vessel_points_mm.size() ? t.vessel_points_mm[flat] : Eigen::Vector3d(1e3 * cp.position_m);
        ++flat;
        pts.push_back({r3(x.x()), r3(x.y()), r3(x.z()), r3(1e3 * cp.radius_m)});
        Eigen::Vector2d cr;
        pix.push_back(g.project(x, &cr) ? px(cr) : nlohmann::json());
      }
      const double opacity = b < t.branch_opacity.size() ? t.branch_opacity[b] : 0.0;
      vessels.push_back(
          {{"branch", br.name},
           {"label", static_cast<int>(b) + 1},
           {"parent", br.parent >= 0 ? nlohmann::json(t.tree->branches[br.parent].name) : nlohmann::json()},
           {"opacity", opacity},
           {"contrast_visible", opacity > t.visible_opacity},
           {"points_mm", pts},
           {"points_px", pix},
           {"points_opacity", ops}});
    }
  }
  return {
      {"frame", t.frame},
      {"sim_time_s", t.time_s},
      {"heart_phase", t.heart_phase},
      {"c_arm",
       {{"primary_deg", t.pose.primary_deg},
        {"secondary_deg", t.pose.secondary_deg},
        {"sid_mm", t.sid_mm},
        {"sad_mm", t.sad_mm},
        {"isocenter_mm", exact(t.pose.isocenter_mm)}}},
      {"projection",
       {{"matrix", matrix},
        {"source_mm", exact(g.source_mm)},
        {"detector_center_mm", exact(g.center_mm)},
        {"u", exact(g.u)},
        {"v", exact(g.v)},
        {"pixel_mm", g.pixel_mm},
        {"width", g.width},
        {"height", g.height}}},
      {"wire",
       {{"nodes_mm", wire_mm},
        {"nodes_px", wire_px},
        {"tip_mm", t.wire_mm.empty() ? nlohmann::json() : v3(t.wire_mm.back())},
        {"tip_px", t.wire_px.empty() ? nlohmann::json() : px(t.wire_px.back())},
        {"tip_branch", t.tip_branch.empty() ? nlohmann::json() : nlohmann::json(t.tip_branch)},
        {"keypoints", keys}}},
      {"vessels", vessels},
      {"mask_pixels", t.mask_pixels},
  };
}

}  // namespace pcisim::dataset
