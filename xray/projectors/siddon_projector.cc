#include "xray/projectors/siddon_projector.h"

#include <stdexcept>

#include "xray/projectors/ray_march.h"

namespace pcisim::xray {

double exact_line_integral(const AttenuationVolume& volume, const Eigen::Vector3d& a_mm, const Eigen::Vector3d& b_mm) {
  // cell coordinates q = index + 1/2: voxel (i, j, k) is the unit cell [i, i+1] x ...
  const Eigen::Vector3d qa = volume.index_from_physical() * a_mm + volume.index_offset() + Eigen::Vector3d::Constant(0.5);
  const Eigen::Vector3d qb = volume.index_from_physical() * b_mm + volume.index_offset() + Eigen::Vector3d::Constant(0.5);
  const double q0[3] = {qa.x(), qa.y(), qa.z()};
  const double dq[3] = {qb.x() - qa.x(), qb.y() - qa.y(), qb.z() - qa.z()};
  const auto& n = volume.dims();
  const double box[3] = {double(n[0]), double(n[1]), double(n[2])};
  double ta = 0.0, tb = 1.0;
  if (!ray::clip_to_box(q0, dq, box, &ta, &tb)) return 0.0;
  const float* mu = volume.padded_mu().data();
  const int64_t px = volume.padded_dims()[0], pxy = px * volume.padded_dims()[1];
  double sum = 0.0;
  auto visit = [&](int i, int j, int k, double t_in, double t_out) {
    sum += double(mu[(i + 1) + px * (j + 1) + pxy * (k + 1)]) * (t_out - t_in);
    return true;
  };
  ray::traverse_cells(q0, dq, ta, tb, n.data(), visit);
  return sum * (b_mm - a_mm).norm();
}

SiddonProjector::SiddonProjector(const AttenuationVolume& volume, int threads) : volume_(volume), pool_(threads) {}

void SiddonProjector::project(const DetectorGeometry& g, Image* image) {
  if (image->width != g.width || image->height != g.height) {
    throw std::invalid_argument("SiddonProjector: image size differs from the detector's");
  }
  auto row = [&](int r) {
    float* out = image->pixels.data() + static_cast<size_t>(r) * g.width;
    for (int c = 0; c < g.width; ++c) {
      out[c] = static_cast<float>(exact_line_integral(volume_, g.source_mm, g.pixel_center_mm(c, r)));
    }
  };
  pool_.for_each_row(g.height, row);
}

}  // namespace pcisim::xray
