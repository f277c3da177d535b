#include "anatomy/phantom/coronary_phantom.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

namespace pcisim::anatomy {
namespace {

using Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr double kStepMm = 0.5;        // centerline point spacing
constexpr double kHeartRadiusMm = 50;  // the heart is a sphere in this phantom
constexpr double kAortaRadiusMm = 14;

// seeded draws; std::uniform_real_distribution differs between standard libraries, this does not
class Draw {
 public:
  explicit Draw(uint32_t seed) : rng_(seed) {}
  // uniform in [-1, 1]
  double unit() { return (static_cast<double>(rng_() >> 8) / double(1u << 24)) * 2.0 - 1.0; }
  // value +- spread, uniform
  double around(double value, double spread) { return value + spread * unit(); }

 private:
  std::mt19937 rng_;
};

// geometry is built in a heart frame (mm): e1 anterior, e2 patient left, e3 = e1 x e2 toward the
// base; the apex is at -e3. polar angle theta from the base pole, azimuth phi from anterior to left.
Vector3d on_shell(double theta_deg, double phi_deg, double radius_mm) {
  const double t = theta_deg * kDeg, p = phi_deg * kDeg;
  return radius_mm * Vector3d(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
}

// rotates v about unit axis n by angle (rad)
Vector3d rotate(const Vector3d& v, const Vector3d& n, double angle) {
  return Eigen::AngleAxisd(angle, n) * v;
}

Vector3d perpendicular_part(const Vector3d& v, const Vector3d& axis) {
  return (v - axis * axis.dot(v)).normalized();
}

// a branch grown by a walker that runs straight for a while (inside the aorta), then stays on the
// epicardial shell and steers toward waypoints with bounded curvature, plus a seeded wiggle.
struct Walk {
  Vector3d start_mm;
  Vector3d start_dir;
  double straight_mm = 0.0;
  std::vector<Vector3d> waypoints_mm;  // on the shell
  double length_mm = 0.0;
  double radius0_mm = 1.0, radius1_mm = 1.0;  // linear taper after the straight stretch
  double shell_mm = kHeartRadiusMm + 1.5;
  double max_curvature_per_mm = 1.0 / 12.0;  // the wire must be able to follow it
  double wiggle_per_mm = 0.0, wiggle_wavelength_mm = 30.0, wiggle_phase = 0.0;
};

std::vector<CenterlinePoint> walk(const Walk& w) {
  std::vector<CenterlinePoint> out;
  const int steps = std::max(1, static_cast<int>(std::lround(w.length_mm / kStepMm)));
  out.reserve(steps + 1);
  Vector3d p = w.start_mm;
  Vector3d t = w.start_dir.normalized();
  size_t target = 0;
  for (int i = 0; i <= steps; ++i) {
    const double s = i * kStepMm;
    double r = w.radius0_mm;
    if (s > w.straight_mm && w.length_mm > w.straight_mm) {
      const double f = (s - w.straight_mm) / (w.length_mm - w.straight_mm);
      r = w.radius0_mm + (w.radius1_mm - w.radius0_mm) * std::min(1.0, f);
    }
    out.push_back({p, r});
    if (i == steps) break;
    if (s >= w.straight_mm) {
      const Vector3d n = p.normalized();
      const Vector3d tc = perpendicular_part(t, n);
      // a waypoint counts as reached when close or once passed; after the last one the walker
      // goes on along the heart without steering (a bounded-turn pursuit would orbit it)
      while (target < w.waypoints_mm.size() &&
             ((w.waypoints_mm[target] - p).norm() < 6.0 ||
              (s > w.straight_mm + 10.0 && (w.waypoints_mm[target] - p).dot(tc) < 0.0))) {
        ++target;
      }
      double turn = 0.0;
      if (target < w.waypoints_mm.size()) {
        const Vector3d want = perpendicular_part(w.waypoints_mm[target] - p, n);
        const double angle = std::atan2(tc.cross(want).dot(n), tc.dot(want));
        const double max_turn = w.max_curvature_per_mm * kStepMm;
        turn = std::clamp(angle, -max_turn, max_turn);
      }
      turn += w.wiggle_per_mm * kStepMm * std::sin(2 * kPi * s / w.wiggle_wavelength_mm + w.wiggle_phase);
      // relax the radius onto the epicardial shell over ~10 mm instead of jumping onto it
      const double radial = std::clamp((w.shell_mm - p.norm()) / 10.0, -0.5, 0.5);
      const Vector3d want_t = (rotate(tc, n, turn) + radial * n).normalized();
      // the heading itself turns by at most the curvature bound (no kink where the walk begins)
      const double bend = std::atan2(t.cross(want_t).norm(), t.dot(want_t));
      const double max_bend = (w.max_curvature_per_mm + std::abs(w.wiggle_per_mm)) * kStepMm;
      if (bend > max_bend) {
        t = rotate(t, t.cross(want_t).normalized(), max_bend);
      } else {
        t = want_t;
      }
    }
    p += kStepMm * t;
  }
  return out;
}

}  // namespace

VesselTree make_coronary_phantom(const CoronaryPhantomSpec& spec) {
  Draw draw(spec.seed);

  // heart frame -> patient LPS: the base points right, posterior and superior
  const Vector3d base_dir = Vector3d(-0.45, 0.35, 0.82).normalized();
  const Vector3d anterior = perpendicular_part(Vector3d(0, -1, 0), base_dir);
  Eigen::Matrix3d heart_to_patient;
  heart_to_patient.col(0) = anterior;
  heart_to_patient.col(1) = base_dir.cross(anterior);
  heart_to_patient.col(2) = base_dir;
  const Eigen::Matrix3d patient_to_heart = heart_to_patient.transpose();

  // ascending aorta: superior, slightly right and anterior (patient frame), then into heart frame
  const Vector3d aorta_dir =
      patient_to_heart * Vector3d(draw.around(-0.2, 0.05), draw.around(-0.1, 0.05), 1.0).normalized();
  const Vector3d aorta_bend = perpendicular_part(patient_to_heart * Vector3d(0.3, 0.6, 0.2), aorta_dir);

  // the LM aims at a point on the epicardial shell, left and anterior of the aortic root; the
  // aorta is placed so the LM leaves its centerline
  const double shell_mm = kHeartRadiusMm + 2.0;
  const Vector3d lm_aim_mm = on_shell(draw.around(38, 3), draw.around(55, 5), shell_mm);
  const Vector3d lm_dir = perpendicular_part(Vector3d(draw.around(0.2, 0.1), 1.0, draw.around(-0.25, 0.1)), aorta_dir);
  const double lm_outside_mm = draw.around(10.0, 1.0);
  const double lm_length_mm = std::round((kAortaRadiusMm + lm_outside_mm) / kStepMm) * kStepMm;
  // the LM leaves the aorta's centerline 10 mm above the root; the aorta is placed to match
  const int lm_parent_point = 20;
  const Vector3d lm_start_mm = lm_aim_mm - lm_length_mm * lm_dir;

  VesselTree tree;
  auto add = [&tree](std::string name, int parent, int parent_point, std::vector<CenterlinePoint> points) {
    tree.branches.push_back({std::move(name), parent, parent_point, std::move(points)});
    return static_cast<int>(tree.branches.size()) - 1;
  };

  // aorta: 60 mm, gently curving toward the arch
  std::vector<CenterlinePoint> aorta;
  const double aorta_bend_radius_mm = draw.around(140, 20);
  const double aorta_radius_mm = draw.around(kAortaRadiusMm, 0.5);
  for (int i = 0; i <= 120; ++i) {
    const double s = (i - lm_parent_point) * kStepMm;
    aorta.push_back({lm_start_mm + s * aorta_dir + (s * s / (2 * aorta_bend_radius_mm)) * aorta_bend, aorta_radius_mm});
  }
  const int aorta_id = add("aorta", -1, -1, aorta);

  // LM: straight from the aortic centerline through the left sinus ostium, then bending onto the
  // heart's surface (as the real LM lies on it), so the wire meets the fork nearly tangentially
  Walk lm;
  lm.start_mm = lm_start_mm;
  lm.start_dir = lm_dir;
  lm.straight_mm = kAortaRadiusMm + 1.0;
  lm.length_mm = lm_length_mm;
  lm.shell_mm = shell_mm;
  lm.waypoints_mm = {(lm_aim_mm + 20.0 * perpendicular_part(lm_dir, lm_aim_mm.normalized())).normalized() * shell_mm};
  lm.radius0_mm = lm.radius1_mm = draw.around(2.0, 0.1);
  const auto lm_points = walk(lm);
  const int lm_id = add("LM", aorta_id, lm_parent_point, lm_points);
  const int lm_end = static_cast<int>(lm_points.size()) - 1;

  // the fork: LAD and LCx leave the LM's end, split ~66 deg about the LM's heading along the heart
  // and keeping the LM's slope off the surface (no kink), then settle onto the epicardium
  const Vector3d fork = lm_points[lm_end].position_m;
  const Vector3d lm_end_dir = (fork - lm_points[lm_end - 1].position_m).normalized();
  const Vector3d fork_n = fork.normalized();
  const Vector3d lm_heading = perpendicular_part(lm_end_dir, fork_n);
  const Vector3d lm_rise = fork_n * fork_n.dot(lm_end_dir);
  double sign = 1.0;  // LAD turns toward anterior (+e1)
  if (rotate(lm_heading, fork_n, 0.5).x() < rotate(lm_heading, fork_n, -0.5).x()) sign = -1.0;
  const double lad_turn = draw.around(33, 3) * kDeg, lcx_turn = draw.around(33, 3) * kDeg;
  auto daughter_dir = [&](double turn) {
    return (rotate(lm_heading, fork_n, turn) * std::sqrt(1.0 - lm_rise.squaredNorm()) + lm_rise).normalized();
  };

  const double shell = kHeartRadiusMm + 1.5;
  Walk lad;
  lad.start_mm = fork;
  lad.start_dir = daughter_dir(sign * lad_turn);
  lad.waypoints_mm = {on_shell(draw.around(70, 4), draw.around(22, 4), shell),
                      on_shell(draw.around(120, 4), draw.around(25, 5), shell),
                      on_shell(draw.around(165, 4), draw.around(60, 8), shell), on_shell(150, 200, shell)};
  lad.length_mm = draw.around(120, 8);
  lad.radius0_mm = draw.around(1.8, 0.05);
  lad.radius1_mm = draw.around(0.8, 0.04);
  lad.wiggle_per_mm = draw.around(0.02, 0.01);
  lad.wiggle_phase = draw.around(0, kPi);
  const auto lad_points = walk(lad);
  const int lad_id = add("LAD", lm_id, lm_end, lad_points);

  Walk lcx;
  lcx.start_mm = fork;
  lcx.start_dir = daughter_dir(-sign * lcx_turn);
  // the AV groove is nearly a circle; the groove's undulation makes the LCx non-planar
  lcx.waypoints_mm = {on_shell(draw.around(50, 2), draw.around(95, 5), shell),
                      on_shell(draw.around(60, 2), draw.around(130, 5), shell),
                      on_shell(draw.around(50, 2), draw.around(165, 5), shell),
                      on_shell(draw.around(68, 3), draw.around(200, 5), shell), on_shell(90, 235, shell)};
  lcx.length_mm = draw.around(80, 6);
  lcx.radius0_mm = draw.around(1.6, 0.05);
  lcx.radius1_mm = draw.around(0.8, 0.04);
  lcx.wiggle_per_mm = draw.around(0.02, 0.01);
  lcx.wiggle_phase = draw.around(0, kPi);
  const auto lcx_points = walk(lcx);
  const int lcx_id = add("LCx", lm_id, lm_end, lcx_points);

  // side branches leave their parent at an angle about the local heart normal, then steer
  // toward a waypoint given relative to the branch point (theta, phi offsets on the shell)
  auto side = [&](const char* name, int parent, const std::vector<CenterlinePoint>& parent_points, double at_mm,
                  double angle_deg, double dtheta_deg, double dphi_deg, double length_mm) {
    const int k =
        std::clamp(static_cast<int>(std::lround(at_mm / kStepMm)), 1, static_cast<int>(parent_points.size()) - 2);
    const Vector3d p = parent_points[k].position_m;
    const Vector3d n = p.normalized();
    const Vector3d tangent = perpendicular_part(parent_points[k + 1].position_m - parent_points[k - 1].position_m, n);
    const double theta = std::acos(std::clamp(p.z() / p.norm(), -1.0, 1.0)) / kDeg;
    const double phi = std::atan2(p.y(), p.x()) / kDeg;
    const Vector3d target = on_shell(theta + dtheta_deg, phi + dphi_deg, shell);
    // turn the start direction toward the side of the target
    const Vector3d to_target = perpendicular_part(target - p, n);
    const double s = tangent.cross(to_target).dot(n) >= 0 ? 1.0 : -1.0;
    Walk w;
    w.start_mm = p;
    w.start_dir = rotate(tangent, n, s * angle_deg * kDeg);
    w.waypoints_mm = {target};
    w.length_mm = length_mm;
    w.radius0_mm = std::min(draw.around(0.95, 0.05), parent_points[k].radius_m);
    w.radius1_mm = draw.around(0.65, 0.05);
    w.wiggle_per_mm = draw.around(0.02, 0.01);
    w.wiggle_phase = draw.around(0, kPi);
    add(name, parent, k, walk(w));
  };
  side("D1", lad_id, lad_points, draw.around(22, 3), draw.around(45, 5), 55, 40, draw.around(55, 5));
  side("D2", lad_id, lad_points, draw.around(52, 3), draw.around(45, 5), 45, 40, draw.around(45, 5));
  side("OM1", lcx_id, lcx_points, draw.around(25, 3), draw.around(50, 5), 60, 15, draw.around(55, 5));
  side("OM2", lcx_id, lcx_points, draw.around(52, 3), draw.around(50, 5), 55, 10, draw.around(45, 5));

  // RCA: from the right sinus, along the right AV groove to the crux, then down (PDA)
  Walk rca;
  const int rca_parent_point = 24;
  rca.start_mm = aorta[rca_parent_point].position_m;
  rca.start_dir = perpendicular_part(patient_to_heart * Vector3d(-1.0, draw.around(-0.6, 0.1), -0.1), aorta_dir);
  rca.straight_mm = kAortaRadiusMm + 2.0;
  rca.waypoints_mm = {on_shell(draw.around(55, 3), draw.around(-45, 5), shell),
                      on_shell(draw.around(60, 3), draw.around(-110, 5), shell),
                      on_shell(draw.around(68, 3), draw.around(-170, 5), shell),
                      on_shell(draw.around(110, 4), draw.around(-185, 5), shell)};
  rca.length_mm = draw.around(120, 8);
  rca.radius0_mm = draw.around(1.8, 0.05);
  rca.radius1_mm = draw.around(0.9, 0.04);
  rca.wiggle_per_mm = draw.around(0.02, 0.01);
  rca.wiggle_phase = draw.around(0, kPi);
  add("RCA", aorta_id, rca_parent_point, walk(rca));

  // to metres, patient frame
  for (auto& b : tree.branches) {
    for (auto& p : b.points) {
      p.position_m = heart_to_patient * p.position_m * 1e-3;
      p.radius_m *= 1e-3;
    }
  }
  return tree;
}

std::vector<Eigen::Vector3d> guide_catheter_path(const VesselTree& tree) {
  std::vector<Eigen::Vector3d> path;
  const int aorta = tree.find("aorta"), lm = tree.find("LM");
  if (aorta < 0 || lm < 0) return path;
  const auto& ao = tree.branches[aorta].points;
  const auto& lm_points = tree.branches[lm].points;
  if (ao.size() < 2 || lm_points.size() < 2) return path;

  // a cubic bezier: down the ascending aorta, curving round into the LM's direction (a JL-like
  // curve). It starts on the aortic centerline 45 mm above the LM's branch point.
  const int start_index = std::min<int>(ao.size() - 1, tree.branches[lm].parent_point + 90);
  const Vector3d p0 = ao[start_index].position_m;
  const Vector3d p3 = lm_points.front().position_m;
  const Vector3d down = (ao[std::max(0, start_index - 1)].position_m - p0).normalized();
  const Vector3d lm_dir = (lm_points[1].position_m - p3).normalized();
  const double reach_m = (p3 - p0).norm();
  // the tip's last 3 mm are straight and coaxial with the LM, like an engaged catheter's tip
  const Vector3d tip_base = p3 - 0.003 * lm_dir;
  const Vector3d p1 = p0 + 0.5 * reach_m * down;
  const Vector3d p2 = tip_base - 0.008 * lm_dir;  // inside the 14 mm aortic root

  // dense samples, then resample at equal arc length so the spacing is ~0.5 mm
  constexpr int kCurve = 2000, kTip = 60, kDense = kCurve + kTip;
  std::vector<Vector3d> dense(kDense + 1);
  std::vector<double> arc(kDense + 1, 0.0);
  for (int i = 0; i <= kDense; ++i) {
    if (i <= kCurve) {
      const double u = double(i) / kCurve, v = 1.0 - u;
      dense[i] = v * v * v * p0 + 3 * v * v * u * p1 + 3 * v * u * u * p2 + u * u * u * tip_base;
    } else {
      dense[i] = tip_base + (double(i - kCurve) / kTip) * (p3 - tip_base);
    }
    if (i > 0) arc[i] = arc[i - 1] + (dense[i] - dense[i - 1]).norm();
  }
  const int n = std::max(1, static_cast<int>(std::ceil(arc.back() / 0.5e-3)));
  path.reserve(n + 1);
  int j = 0;
  for (int k = 0; k < n; ++k) {
    const double s = arc.back() * k / n;
    while (j + 1 < kDense && arc[j + 1] < s) ++j;
    const double seg = arc[j + 1] - arc[j];
    const double f = seg > 0 ? (s - arc[j]) / seg : 0.0;
    path.push_back(dense[j] + f * (dense[j + 1] - dense[j]));
  }
  path.push_back(p3);  // exactly the LM's first point
  return path;
}

}  // namespace pcisim::anatomy
