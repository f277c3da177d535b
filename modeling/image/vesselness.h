#pragma once
// Frangi's vesselness of bright tubes (A. F. Frangi et al., "Multiscale vessel enhancement
// filtering", MICCAI 1998, eqs 11-15), computed only at the voxels asked for: the CTA pipeline's
// tube growth needs it at a few million voxels of a crop of tens of millions (ITK's multi-scale
// filter computed it everywhere: 30-50 s a family case on 2 cores; issue #30).
//
// At each scale sigma the image is smoothed by a Gaussian of sigma (mm, per axis in voxels) and
// its Hessian H taken by central differences (mm^-2), normalised by sigma^2 so that scales
// compare. With H's eigenvalues ordered by magnitude, |l1| <= |l2| <= |l3|, a bright tube has
// l1 ~ 0 along it and l2, l3 strongly negative across it:
//   V = 0                                                   if l2 > 0 or l3 > 0
//   V = (1 - exp(-Ra^2 / 2 alpha^2)) exp(-Rb^2 / 2 beta^2) (1 - exp(-S^2 / 2 gamma^2))
//   Ra = |l2| / |l3|  (a tube, not a sheet),  Rb = |l1| / sqrt(|l2 l3|)  (a tube, not a blob),
//   S = sqrt(l1^2 + l2^2 + l3^2)  (structure, not flat noise)
// and the measure is the largest V over the scales.
#include "modeling/image/image3.h"

namespace pcisim::modeling {

struct VesselnessOptions {
  double sigma_min_mm = 0.4, sigma_max_mm = 1.0;
  int sigma_steps = 3;  // equispaced from min to max
  double alpha = 0.5, beta = 0.5;
  double gamma = 100;  // the structure strength (image units, here HU) that counts
  int threads = 1;
};

// V at the voxels `where` marks (0 elsewhere); `where` on image's grid, or nullptr for every voxel;
// throws std::invalid_argument when the image or the mask does not hold one value per voxel
FloatImage bright_tube_vesselness(const FloatImage& image, const Mask* where, const VesselnessOptions& options);

// the three eigenvalues of the symmetric matrix [[a, d, e], [d, b, f], [e, f, c]], ordered by
// magnitude (|l[0]| <= |l[1]| <= |l[2]|); closed form (the trigonometric solution of the
// characteristic cubic)
std::array<double, 3> symmetric_eigenvalues_by_magnitude(double a, double b, double c, double d, double e, double f);

}  // namespace pcisim::modeling
