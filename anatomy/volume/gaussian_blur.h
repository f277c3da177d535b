#pragma once
// A separable Gaussian blur of a float volume (x fastest), in place: the scanner's point spread in
// the phantom CTAs (anatomy/phantom/phantom_cta.cc) and the noise smoothing before the CTA
// pipeline's lumen fill (modeling/cta/lumen_segmentation.cc).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace pcisim::anatomy {

// sigma per axis in voxels (an axis with sigma <= 0.05 is left alone); the kernel reaches 3 sigma,
// normalised; edges replicated; slices (or rows) shared over `threads` (>= 1)
void gaussian_blur(std::vector<float>* data, const std::array<int64_t, 3>& dims, const Eigen::Vector3d& sigma_vox,
                   int threads);

}  // namespace pcisim::anatomy
