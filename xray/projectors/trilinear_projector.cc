#include "xray/projectors/trilinear_projector.h"

#include <stdexcept>

#include "xray/projectors/ray_packet.h"
#include "xray/projectors/views.h"

namespace pcisim::xray {

TrilinearProjector::TrilinearProjector(const AttenuationVolume& volume, const TrilinearOptions& options)
    : volume_(volume), options_(options), pool_(options.threads) {
  set_options(options);
}

void TrilinearProjector::set_options(const TrilinearOptions& options) {
  if (!(options.step_voxels > 0)) throw std::invalid_argument("TrilinearProjector: step_voxels must be > 0");
  options_ = options;
}

void TrilinearProjector::project(const AttenuationVolume& volume, const DetectorGeometry& g, Image* image) {
  if (image->width != g.width || image->height != g.height) {
    throw std::invalid_argument("TrilinearProjector: image size differs from the detector's");
  }
  const ray::GridView grid = grid_view(volume);
  const ray::DetectorView det = detector_view(g);
  const float step = static_cast<float>(options_.step_voxels);
  const bool skip = options_.skip_empty;
  // the packets gather with 32-bit indices: grids past 2^31 voxels go one ray at a time
  const bool small_enough = volume.padded_count() < (size_t(1) << 31) - 1;
  const int packed = options_.packets && small_enough && ray::packet_supported() ? g.width / 8 * 8 : 0;
  const bool slices = options_.slices;
  auto row = [&](int r) {
    float* out = image->pixels.data() + static_cast<size_t>(r) * g.width;
    if (slices) {
      for (int c = 0; c < packed; c += 8) ray::slice_rays_x8(grid, det, c, r, skip, out + c);
      for (int c = packed; c < g.width; ++c) out[c] = ray::slice_ray(grid, det, c, r, skip);
      return;
    }
    for (int c = 0; c < packed; c += 8) ray::trilinear_rays_x8(grid, det, c, r, step, skip, out + c);
    for (int c = packed; c < g.width; ++c) out[c] = ray::trilinear_ray(grid, det, c, r, step, skip);
  };
  pool_.for_each_row(g.height, row);
}

}  // namespace pcisim::xray
