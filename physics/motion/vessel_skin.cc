#include "physics/motion/vessel_skin.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "physics/param_checks.h"
#include "physics/sdf/sdf_kernels.h"

namespace pcisim::physics {
namespace {

sdf::V3 v3(const Eigen::Vector3d& p) {
  return {p.x(), p.y(), p.z()};
}
Eigen::Vector3d ev(const sdf::V3& p) {
  return {p.x, p.y, p.z};
}

// a triangle's orientation: columns edge 1's direction, the in-plane direction across it, the
// unit normal (orthonormal)
Eigen::Matrix3d orientation(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  Eigen::Matrix3d f;
  f.col(0) = (b - a).normalized();
  f.col(2) = (b - a).cross(c - a).normalized();
  f.col(1) = f.col(2).cross(f.col(0));
  return f;
}

// a triangle's affine frame: columns edge 1, edge 2, unit normal
Eigen::Matrix3d frame(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  Eigen::Matrix3d f;
  f.col(0) = b - a;
  f.col(1) = c - a;
  const Eigen::Vector3d n = f.col(0).cross(f.col(1));
  const double len = n.norm();
  f.col(2) = len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::UnitZ();
  return f;
}

}  // namespace

void validate(const VesselMotionParams& m) {
  require(kMotionAttachDistanceM.contains(m.attach_distance_m),
          "vessel_motion.attach_distance_m: expected " + kMotionAttachDistanceM.describe() + " m");
  require(kMotionFadeDistanceM.contains(m.fade_distance_m),
          "vessel_motion.fade_distance_m: expected " + kMotionFadeDistanceM.describe() + " m");
  require(kMotionBlendRadiusM.contains(m.blend_radius_m),
          "vessel_motion.blend_radius_m: expected " + kMotionBlendRadiusM.describe() + " m");
}

VesselSkin::VesselSkin(const anatomy::VesselTree& rest_tree, const Eigen::Matrix3Xd& rest_surface_m,
                       std::span<const std::array<int, 3>> triangles, const VesselMotionParams& params)
    : params_(params), triangles_(triangles.begin(), triangles.end()) {
  const int surface_n = static_cast<int>(rest_surface_m.cols());
  for (const auto& t : triangles_)
    for (int v : t)
      if (v < 0 || v >= surface_n)
        throw std::invalid_argument("vessel_motion: an epicardial triangle indexes past the surface");
  validate(params);

  // flatten the tree
  offsets_.push_back(0);
  for (const auto& b : rest_tree.branches) {
    for (const auto& p : b.points) rest_.push_back(p.position_m);
    offsets_.push_back(static_cast<int>(rest_.size()));
  }
  now_ = rest_;
  before_ = rest_;
  const int n = point_count();
  binding_.resize(n);
  weight_.assign(n, 0.0);
  turn_.assign(n, Eigen::Quaterniond::Identity());

  // bind each point to its nearest triangle (brute force: built once, ~1e3 points x ~1e3 triangles)
  for (int i = 0; i < n; ++i) {
    const sdf::V3 p = v3(rest_[i]);
    double best = std::numeric_limits<double>::infinity();
    for (int t = 0; t < static_cast<int>(triangles_.size()); ++t) {
      const auto& tri = triangles_[t];
      int region = 0;
      const sdf::V3 q = sdf::closest_on_triangle(p, v3(rest_surface_m.col(tri[0])), v3(rest_surface_m.col(tri[1])),
                                                 v3(rest_surface_m.col(tri[2])), &region);
      const double d = (ev(q) - rest_[i]).squaredNorm();
      if (d < best) {
        best = d;
        binding_[i].tri = t;
      }
    }
    if (binding_[i].tri < 0) continue;  // no surface: the tree stands still
    const auto& tri = triangles_[binding_[i].tri];
    const Eigen::Matrix3d f = frame(rest_surface_m.col(tri[0]), rest_surface_m.col(tri[1]), rest_surface_m.col(tri[2]));
    binding_[i].coords = f.colPivHouseholderQr().solve(rest_[i] - rest_surface_m.col(tri[0]));
    binding_[i].rest_orientation =
        orientation(rest_surface_m.col(tri[0]), rest_surface_m.col(tri[1]), rest_surface_m.col(tri[2]));
    const double beyond = std::sqrt(best) - params_.attach_distance_m;
    weight_[i] = beyond <= 0.0 ? 1.0 : std::max(0.0, 1.0 - beyond / std::max(params_.fade_distance_m, 1e-9));
  }

  // rest-frame grid of the centerline points for the blend (cell = blend radius: a query reads
  // its own cell and the 26 around it)
  cell_m_ = params_.blend_radius_m;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& p : rest_) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (n == 0) return;
  grid_origin_m_ = lo - Eigen::Vector3d::Constant(cell_m_);
  for (int k = 0; k < 3; ++k) grid_dims_[k] = static_cast<int>(std::ceil((hi[k] - lo[k]) / cell_m_)) + 3;
  const size_t cells = static_cast<size_t>(grid_dims_.x()) * grid_dims_.y() * grid_dims_.z();
  if (cells > 64u << 20) throw std::invalid_argument("vessel_motion.blend_radius_m: too small for the tree's extent");
  std::vector<int> cell_of(n);
  cell_start_.assign(cells + 1, 0);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3i c = ((rest_[i] - grid_origin_m_) / cell_m_).array().floor().cast<int>();
    cell_of[i] = (c.z() * grid_dims_.y() + c.y()) * grid_dims_.x() + c.x();
    ++cell_start_[cell_of[i] + 1];
  }
  for (size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  cell_points_.resize(n);
  std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (int i = 0; i < n; ++i) cell_points_[fill[cell_of[i]]++] = i;
}

Eigen::Vector3d VesselSkin::skinned(const Binding& b, const Eigen::Matrix3Xd& surface_m) const {
  const auto& tri = triangles_[b.tri];
  const Eigen::Matrix3d f = frame(surface_m.col(tri[0]), surface_m.col(tri[1]), surface_m.col(tri[2]));
  return surface_m.col(tri[0]) + f * b.coords;
}

void VesselSkin::update(const Eigen::Matrix3Xd& surface_m) {
  std::copy(now_.begin(), now_.end(), before_.begin());
  for (int i = 0; i < point_count(); ++i) {
    const Binding& b = binding_[i];
    if (b.tri < 0 || weight_[i] <= 0.0) {
      now_[i] = rest_[i];
      turn_[i].setIdentity();
      continue;
    }
    now_[i] = rest_[i] + weight_[i] * (skinned(b, surface_m) - rest_[i]);
    // its triangle's turn since rest, as much of it as the point rides the heart
    const auto& tri = triangles_[b.tri];
    const Eigen::Matrix3d now = orientation(surface_m.col(tri[0]), surface_m.col(tri[1]), surface_m.col(tri[2]));
    const Eigen::Quaterniond q(Eigen::Matrix3d(now * b.rest_orientation.transpose()));
    turn_[i] = Eigen::Quaterniond::Identity().slerp(weight_[i], q);
  }
}

template <class F>
double VesselSkin::blend(const Eigen::Vector3d& p, F&& f) const {
  if (cell_points_.empty() || !p.allFinite()) return 0.0;
  const Eigen::Vector3d g = (p - grid_origin_m_) / cell_m_;
  Eigen::Vector3i c;
  for (int k = 0; k < 3; ++k) {
    if (!(g[k] >= 0.0) || g[k] >= grid_dims_[k]) return 0.0;
    c[k] = static_cast<int>(g[k]);
  }
  // inverse squared distance over the centerline points within the blend radius; the softening
  // keeps a point on a centerline from taking one sample's value alone
  const double r2 = params_.blend_radius_m * params_.blend_radius_m;
  const double soft2 = 0.01 * r2;
  double wsum = 0.0;
  for (int z = std::max(c.z() - 1, 0); z <= std::min(c.z() + 1, grid_dims_.z() - 1); ++z)
    for (int y = std::max(c.y() - 1, 0); y <= std::min(c.y() + 1, grid_dims_.y() - 1); ++y)
      for (int x = std::max(c.x() - 1, 0); x <= std::min(c.x() + 1, grid_dims_.x() - 1); ++x) {
        const int cell = (z * grid_dims_.y() + y) * grid_dims_.x() + x;
        for (int k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
          const int i = cell_points_[k];
          const double d2 = (rest_[i] - p).squaredNorm();
          if (d2 > r2) continue;
          // fades to zero at the blend radius so the field is continuous as points enter it
          const double w = (1.0 - d2 / r2) / (d2 + soft2);
          f(i, w);
          wsum += w;
        }
      }
  return wsum;
}

Eigen::Vector3d VesselSkin::displacement_m(const Eigen::Vector3d& p, double a) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  const double wsum = blend(p, [&](int i, double w) { sum += w * ((1.0 - a) * before_[i] + a * now_[i] - rest_[i]); });
  return wsum > 0.0 ? Eigen::Vector3d(sum / wsum) : Eigen::Vector3d::Zero();
}

bool VesselSkin::carries(const Eigen::Vector3d& p) const {
  return blend(p, [](int, double) {}) > 0.0;
}

Eigen::Vector3d VesselSkin::turn_to_world(const Eigen::Vector3d& rest_p, const Eigen::Vector3d& v) const {
  if (!v.allFinite() || v.squaredNorm() == 0.0) return v;
  // the blend of the nearby centerline points' turns (their quaternions on one hemisphere)
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();
  const Eigen::Quaterniond* first = nullptr;
  const double wsum = blend(rest_p, [&](int i, double w) {
    if (!first) first = &turn_[i];
    const double sign = first->coeffs().dot(turn_[i].coeffs()) < 0.0 ? -1.0 : 1.0;
    sum += sign * w * turn_[i].coeffs();
  });
  if (!(wsum > 0.0) || !(sum.norm() > 0.0)) return v;
  Eigen::Quaterniond q;
  q.coeffs() = sum.normalized();
  return q * v;
}

Eigen::Vector3d VesselSkin::to_rest(const Eigen::Vector3d& world_p) const {
  // start from the displacement of the nearest moved centerline point (the motion can exceed
  // the blend radius, so the world point itself may lie outside every blend)
  int nearest = -1;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < point_count(); ++i) {
    const double d = (now_[i] - world_p).squaredNorm();
    if (d < best) {
      best = d;
      nearest = i;
    }
  }
  Eigen::Vector3d x = nearest >= 0 ? Eigen::Vector3d(world_p - (now_[nearest] - rest_[nearest])) : world_p;
  for (int k = 0; k < 4; ++k) x = world_p - displacement_m(x);
  return x;
}

}  // namespace pcisim::physics
