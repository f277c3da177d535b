#pragma once
// Stage (c), second half: each traced branch (a staircase of voxel centres) as a smooth cubic
// B-spline, as the paper fits its branches. A least-squares fit with a second-difference penalty
// on the control points (a P-spline: Eilers and Marx, Statistical Science 11(2), 1996): clamped
// uniform knots every knot_spacing_mm of arc length, the ends held with a large weight. The curve
// is then sampled every sample_spacing_mm of arc length, the cross-sections of stage (d).
#include <Eigen/Core>
#include <vector>

namespace pcisim::modeling {

struct SplineOptions {
  double knot_spacing_mm = 3.0;    // fewer knots: smoother, less able to follow a tight bend
  double smoothing = 0.1;          // weight of the second-difference penalty
  double sample_spacing_mm = 0.5;  // distance between cross-sections (2 per mm)
};

// the fitted curve sampled along its length; the first and last points are the inputs' ends
// (to within the end weight). Fewer than 2 points are returned as they are.
std::vector<Eigen::Vector3d> fit_and_sample(const std::vector<Eigen::Vector3d>& points_mm,
                                            const SplineOptions& options);

// values v (one per input point) carried onto the samples by arc-length position (linear)
std::vector<double> carry_along(const std::vector<Eigen::Vector3d>& points_mm, const std::vector<double>& v,
                                const std::vector<Eigen::Vector3d>& samples_mm);

}  // namespace pcisim::modeling
