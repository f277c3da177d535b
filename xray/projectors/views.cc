#include "xray/projectors/views.h"

namespace pcisim::xray {

ray::GridView grid_view(const AttenuationVolume& volume) {
  ray::GridView g;
  g.mu = volume.padded_mu();
  g.nx = volume.padded_dims()[0];
  g.ny = volume.padded_dims()[1];
  g.nz = volume.padded_dims()[2];
  const Eigen::Matrix3d& a = volume.index_from_physical();
  const Eigen::Vector3d b = volume.index_offset() + Eigen::Vector3d::Ones();  // padded = index + 1
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) g.m[4 * r + c] = static_cast<float>(a(r, c));
    g.m[4 * r + 3] = static_cast<float>(b[r]);
  }
  g.brick_max = volume.brick_max().data();
  g.brick_near = volume.brick_near().data();
  g.bnx = volume.brick_dims()[0];
  g.bny = volume.brick_dims()[1];
  g.bnz = volume.brick_dims()[2];
  g.brick = volume.brick_voxels();
  return g;
}

ray::DetectorView detector_view(const DetectorGeometry& g) {
  ray::DetectorView d;
  for (int a = 0; a < 3; ++a) {
    d.src[a] = static_cast<float>(g.source_mm[a]);
    d.center[a] = static_cast<float>(g.center_mm[a]);
    d.u[a] = static_cast<float>(g.u[a]);
    d.v[a] = static_cast<float>(g.v[a]);
  }
  d.pixel_mm = static_cast<float>(g.pixel_mm);
  d.width = g.width;
  d.height = g.height;
  return d;
}

}  // namespace pcisim::xray
