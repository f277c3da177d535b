#include "anatomy/heart/template_heart_surface.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <ostream>

#include "anatomy/heart/heart_frame.h"

namespace pcisim::anatomy {
namespace {

using Eigen::Vector3d;
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kSphereMm = 50.0;   // the phantom's kHeartRadiusMm
constexpr int kEpicardiumLevel = 3;  // icosphere subdivisions: 642 vertices, ~6.6 mm edges
constexpr int kCavityLevel = 2;      // 162 vertices per cavity

Vector3d direction(double theta_deg, double phi_deg) {
  const double t = theta_deg * kDeg, p = phi_deg * kDeg;
  return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

// a smooth (C1) bump of height_mm over directions within radius_deg of the centre
struct Bump {
  Vector3d centre;
  double radius_deg;
  double height_mm;
  double at(const Vector3d& u) const {
    const double angle = std::atan2(centre.cross(u).norm(), centre.dot(u)) / kDeg;
    if (angle >= radius_deg) return 0.0;
    const double x = angle / radius_deg;
    return height_mm * (1.0 - x * x) * (1.0 - x * x);
  }
};

const Bump kBumps[] = {
    // left atrium: posterior-left of the base, clear of the LCx in the AV groove (theta >= 43)
    {direction(20, 150), 26, 14.0},
    // right atrium: right-posterior of the base, clear of the RCA (theta >= 53 there)
    {direction(28, -115), 24, 12.0},
    // right atrial appendage over the aortic root, under the proximal RCA as it leaves the
    // aorta and settles onto the AV groove (the RCA rides up to 9 mm off the 50 mm sphere there)
    {direction(29, -19), 18, 6.4},
    // the LM lies in a shallow groove between the aortic root and the LA appendage
    {direction(29.6, 46), 18, -1.6},
};

// icosphere: unit-sphere vertices and outward ccw triangles
void icosphere(int level, std::vector<Vector3d>* v, std::vector<std::array<int, 3>>* t) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  *v = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
        {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  for (auto& p : *v) p.normalize();
  *t = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
        {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
        {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      if (auto it = mid.find(key); it != mid.end()) return it->second;
      v->push_back(((*v)[a] + (*v)[b]).normalized());
      return mid[key] = static_cast<int>(v->size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& f : *t) {
      const int ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      next.insert(next.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    *t = std::move(next);
  }
}

Eigen::Matrix3d cavity_axes(const CavityEllipsoid& c) {
  return Eigen::AngleAxisd(c.azimuth_rad, Vector3d::UnitZ()).toRotationMatrix();
}

}  // namespace

double epicardial_radius_mm(const Vector3d& heart_dir) {
  const Vector3d u = heart_dir.normalized();
  double r = kSphereMm;
  for (const Bump& b : kBumps) r += b.at(u);
  return r;
}

// LV: left-posterior of the septum (the LAD's groove at azimuth ~25 deg, the PDA's at ~190),
// reaching the mitral plane near the AV groove; ~80 ml at end-diastole
CavityEllipsoid lv_cavity() {
  return {{-3.0, 9.5, -6.0}, {24.0, 24.0, 34.0}, 108.0 * kDeg};
}

// RV: a flattened ellipsoid anterior-right of the septum (~25 ml: smaller than a real RV, which
// wraps around the LV as a crescent; the phantom's heart is a 100 mm ball)
CavityEllipsoid rv_cavity() {
  const double az = -55.0 * kDeg;
  return {{33.0 * std::cos(az), 33.0 * std::sin(az), -2.0}, {9.0, 24.0, 29.0}, az};
}

HeartSurface template_heart_surface() {
  HeartSurface s;
  const Eigen::Matrix3d to_patient = heart_to_patient();
  std::vector<Vector3d> unit;
  std::vector<std::array<int, 3>> tris;

  icosphere(kEpicardiumLevel, &unit, &tris);
  for (const auto& u : unit) s.vertices_mm.push_back(to_patient * (epicardial_radius_mm(u) * u));
  for (const auto& t : tris) {
    s.triangles.push_back(t);
    s.markers.push_back(kEpicardium);
  }
  icosphere(kCavityLevel, &unit, &tris);
  for (const auto& [cavity, marker] :
       {std::pair{lv_cavity(), kLvEndocardium}, std::pair{rv_cavity(), kRvEndocardium}}) {
    const int offset = static_cast<int>(s.vertices_mm.size());
    const Eigen::Matrix3d axes = cavity_axes(cavity);
    for (const auto& u : unit)
      s.vertices_mm.push_back(to_patient * (cavity.centre_mm + axes * cavity.semi_axes_mm.cwiseProduct(u)));
    // the tissue's outside is the cavity's inside: reverse the winding
    for (const auto& t : tris) {
      s.triangles.push_back({offset + t[0], offset + t[2], offset + t[1]});
      s.markers.push_back(marker);
    }
    s.holes_mm.push_back(to_patient * cavity.centre_mm);
  }
  return s;
}

void write_tetgen_poly(const HeartSurface& s, std::ostream& out) {
  out.precision(10);
  out << "# template heart PLC (anatomy/heart/template_heart_surface.cc), patient LPS mm\n";
  out << s.vertices_mm.size() << " 3 0 0\n";
  for (size_t i = 0; i < s.vertices_mm.size(); ++i)
    out << i << ' ' << s.vertices_mm[i].x() << ' ' << s.vertices_mm[i].y() << ' ' << s.vertices_mm[i].z() << '\n';
  out << s.triangles.size() << " 1\n";
  for (size_t i = 0; i < s.triangles.size(); ++i)
    out << "1 0 " << s.markers[i] << "\n3 " << s.triangles[i][0] << ' ' << s.triangles[i][1] << ' ' << s.triangles[i][2]
        << '\n';
  out << s.holes_mm.size() << '\n';
  for (size_t i = 0; i < s.holes_mm.size(); ++i)
    out << i << ' ' << s.holes_mm[i].x() << ' ' << s.holes_mm[i].y() << ' ' << s.holes_mm[i].z() << '\n';
  out << "0\n";
}

}  // namespace pcisim::anatomy
