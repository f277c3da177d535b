#include "anatomy/heart/synthetic_heart_motion.h"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "anatomy/heart/heart_frame.h"
#include "anatomy/heart/heart_mesh.h"
#include "anatomy/heart/template_heart_surface.h"

namespace pcisim::anatomy {
namespace {
constexpr double kPi = std::numbers::pi;
constexpr double kApexZMm = -50.0;  // heart frame; the apex holds still (base descends toward it)
}  // namespace

double contraction(double phase, const SyntheticMotionSpec& spec) {
  const double p = phase - std::floor(phase);
  if (p < spec.systole_fraction) return 0.5 * (1.0 - std::cos(kPi * p / spec.systole_fraction));
  const double q = (p - spec.systole_fraction) / spec.filling_fraction;
  return q < 1.0 ? 0.5 * (1.0 + std::cos(kPi * q)) : 0.0;
}

Eigen::Vector3d synthetic_displacement_m(const Eigen::Vector3d& rest_m, double s, const SyntheticMotionSpec& spec) {
  static const Eigen::Matrix3d to_patient = anatomy::heart_to_patient();
  static const anatomy::CavityEllipsoid lv = anatomy::lv_cavity();
  const Eigen::Vector3d x = to_patient.transpose() * rest_m * 1e3;  // heart frame, mm
  // about the LV long axis (through the cavity's centre along e3)
  const Eigen::Vector2d rel(x.x() - lv.centre_mm.x(), x.y() - lv.centre_mm.y());
  const double rho = rel.norm();
  const double zc = (x.z() - lv.centre_mm.z()) / lv.semi_axes_mm.z();
  const double rho_endo = zc * zc < 1.0 ? lv.semi_axes_mm.x() * std::sqrt(1.0 - zc * zc) : 0.0;
  const double lambda = 1.0 - spec.longitudinal_shortening * s;  // long-axis stretch
  const double k = 1.0 - (1.0 - spec.lv_radial_scale_es) * s;    // cavity radius scale
  // the cavity scales by k; outside it each cross-section keeps its wall area times 1/lambda
  // (incompressible), so the endocardium moves in more than the epicardium: the wall thickens
  const double rho_new =
      rho <= rho_endo ? k * rho : std::sqrt(k * k * rho_endo * rho_endo + (rho * rho - rho_endo * rho_endo) / lambda);
  const double psi = s * spec.twist_deg * kPi / 180.0 * (-zc);  // apex one way, base the other
  Eigen::Vector2d rel_new = Eigen::Rotation2Dd(psi) * rel;
  if (rho > 1e-9) rel_new *= rho_new / rho;
  const Eigen::Vector3d x_new(lv.centre_mm.x() + rel_new.x(), lv.centre_mm.y() + rel_new.y(),
                              kApexZMm + lambda * (x.z() - kApexZMm));
  return to_patient * (x_new - x) * 1e-3;
}

MotionGrid template_motion_grid(double h) {
  const Eigen::Matrix3Xd& v = anatomy::template_heart_mesh().vertices_m;
  MotionGrid grid;
  const Eigen::Vector3d lo = v.rowwise().minCoeff().array() - h, hi = v.rowwise().maxCoeff().array() + h;
  grid.origin_m = lo;
  grid.spacing_m = Eigen::Vector3d::Constant(h);
  for (int a = 0; a < 3; ++a) grid.dims[a] = static_cast<int>(std::ceil((hi[a] - lo[a]) / h)) + 1;
  return grid;
}

HeartMotion make_synthetic_heart_motion(const SyntheticMotionSpec& spec) {
  const MotionGrid grid = template_motion_grid(spec.grid_spacing_m);
  const double h = spec.grid_spacing_m;
  std::vector<float> data;
  data.reserve(static_cast<size_t>(spec.frames) * grid.node_count() * 3);
  for (int f = 0; f < spec.frames; ++f) {
    const double s = contraction(static_cast<double>(f) / spec.frames, spec);
    for (int k = 0; k < grid.dims.z(); ++k)
      for (int j = 0; j < grid.dims.y(); ++j)
        for (int i = 0; i < grid.dims.x(); ++i) {
          const Eigen::Vector3d d = synthetic_displacement_m(grid.origin_m + h * Eigen::Vector3d(i, j, k), s, spec);
          data.insert(data.end(), {float(d.x()), float(d.y()), float(d.z())});
        }
  }
  return HeartMotion(grid, spec.frames, spec.cycle_s, std::move(data));
}

}  // namespace pcisim::anatomy
