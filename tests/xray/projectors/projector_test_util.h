#pragma once
// Volumes and geometries for the projector tests: small, seeded.
#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "xray/geometry/detector_geometry.h"
#include "anatomy/volume/volume.h"

namespace pcisim::xray::testing {

inline double uniform(std::mt19937& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng() >> 8) / double(1u << 24));
}

// a rotated, anisotropic volume; smooth: a few Gaussian blobs (so interpolation converges),
// else independent random HU per voxel (for the exact projector)
inline anatomy::Volume random_volume(std::mt19937& rng, bool smooth) {
  anatomy::Volume v = anatomy::Volume::make(
      {int64_t(uniform(rng, 14, 24)), int64_t(uniform(rng, 14, 24)), int64_t(uniform(rng, 12, 20))},
      Eigen::Vector3d(uniform(rng, 0.6, 1.4), uniform(rng, 0.6, 1.4), uniform(rng, 0.8, 2.0)),
      Eigen::Vector3d(uniform(rng, -20, 20), uniform(rng, -20, 20), uniform(rng, -20, 20)),
      anatomy::VoxelType::kFloat32);
  const Eigen::Vector3d axis =
      Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)).normalized();
  v.direction = Eigen::AngleAxisd(uniform(rng, -3, 3), axis).toRotationMatrix();
  struct Blob {
    Eigen::Vector3d c;
    double r, hu;
  };
  std::vector<Blob> blobs;
  for (int b = 0; b < 6; ++b) {
    blobs.push_back({Eigen::Vector3d(uniform(rng, 0.2, 0.8) * v.dims[0], uniform(rng, 0.2, 0.8) * v.dims[1],
                                     uniform(rng, 0.2, 0.8) * v.dims[2]),
                     uniform(rng, 2.5, 5.0), uniform(rng, 300, 1500)});
  }
  for (int64_t k = 0; k < v.dims[2]; ++k) {
    for (int64_t j = 0; j < v.dims[1]; ++j) {
      for (int64_t i = 0; i < v.dims[0]; ++i) {
        double hu;
        if (smooth) {
          hu = -1000;
          for (const Blob& b : blobs) {
            hu += b.hu * std::exp(-(Eigen::Vector3d(i, j, k) - b.c).squaredNorm() / (2 * b.r * b.r));
          }
        } else {
          hu = uniform(rng, -1000, 1500);
        }
        v.hu_f32[v.linear_index(i, j, k)] = static_cast<float>(hu);
      }
    }
  }
  return v;
}

// a cone beam from a random direction, the detector's footprint covering the volume
inline DetectorGeometry random_geometry(std::mt19937& rng, const anatomy::Volume& v, int width, int height) {
  const Eigen::Vector3d c = v.center_mm();
  const double size = (v.spacing_mm.cwiseProduct(Eigen::Vector3d(v.dims[0], v.dims[1], v.dims[2]))).norm();
  const Eigen::Vector3d d = Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)).normalized();
  DetectorGeometry g;
  g.source_mm = c - uniform(rng, 1.5, 3.0) * size * d;
  g.center_mm = c + uniform(rng, 0.8, 1.5) * size * d;
  Eigen::Vector3d u = d.unitOrthogonal();
  u = Eigen::AngleAxisd(uniform(rng, -3, 3), d) * u;
  g.u = u;
  g.v = d.cross(u).normalized();
  g.width = width;
  g.height = height;
  const double magnification = (g.center_mm - g.source_mm).norm() / (c - g.source_mm).norm();
  g.pixel_mm = 1.1 * size * magnification / std::min(width, height);
  return g;
}

}  // namespace pcisim::xray::testing
