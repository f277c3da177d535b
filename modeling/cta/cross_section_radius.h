#pragma once
// Stage (d) of the CTA pipeline (docs/modeling.md): the lumen radius at a centerline sample from a
// 2-D level set on the cross-section there [heart eq 2]. The plane normal to the centerline is
// resampled from the CT (trilinear), smoothed, and a contour started as a small circle at the
// centre moves outward at speed v held back by the edge function g = 1 / (1 + (|grad I| / k)^p)
// [heart eq 2] and drawn onto the edge by grad g (the geodesic active contour of Caselles, Kimmel
// and Sapiro 1997, the paper's reference [7]):
//   Phi_t = -g (v - eps kappa) |grad Phi| + a grad g . grad Phi,   Phi < 0 inside,
// with |grad I| taken relative to its largest value in the section (so k is unitless) and upwind
// differences (Osher and Sethian). The radius is the median, over rays from the centre, of the
// distance to the zero level: a side branch or a touching vessel that the contour runs into moves
// a few rays, not the median.
#include <Eigen/Core>
#include <vector>
#include "modeling/image/image3.h"

namespace pcisim::modeling {

struct RadiusOptions {
  double pixels_per_radius = 8;  // section pixel = guess / this, within [0.05, 0.2] mm
  double field_radii = 2.5;      // the section spans this many guessed radii (+ 0.6 mm) from the centre
  double presmooth_mm = 0.2;     // Gaussian smoothing of the section
  double edge_k = 1.0;           // k of g, relative to the section's largest gradient
  double edge_power = 2;         // p of g
  double balloon_v = 1.0;        // v, pixels per unit time
  double curvature_eps = 0.3;    // eps
  double attraction = 5.0;       // weight of the grad g . grad Phi term
  int iterations = 150;          // at most
  int rays = 32;
};

// reusable buffers (the pipeline calls this ~2 times per mm of centerline)
struct RadiusWorkspace {
  std::vector<float> image, smooth, g, gx, gy, phi, next;
};

// the radius (mm) at centre_mm in the plane normal to tangent; guess_mm from the distance map sets
// the section's scale. The result is capped at the section's half-width.
double cross_section_radius(const FloatImage& hu, const Eigen::Vector3d& centre_mm, const Eigen::Vector3d& tangent,
                            double guess_mm, const RadiusOptions& options, RadiusWorkspace* ws);

}  // namespace pcisim::modeling
