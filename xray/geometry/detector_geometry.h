#pragma once
// A flat-panel cone beam: a point source and a detector plane of width x height square pixels.
// Pixel (c, r) has its centre at center_mm + (c - (W-1)/2) pixel_mm u + (r - (H-1)/2) pixel_mm v;
// c runs along u (image columns, left to right), r along v (rows, top to bottom); row 0 first.
// All positions are in the volume's physical frame (patient LPS, mm).
#include <Eigen/Core>
#include <string>

namespace pcisim::xray {

struct DetectorGeometry {
  Eigen::Vector3d source_mm = Eigen::Vector3d(0, 750, 0);
  Eigen::Vector3d center_mm = Eigen::Vector3d(0, -350, 0);
  Eigen::Vector3d u = Eigen::Vector3d::UnitX();   // unit, along columns
  Eigen::Vector3d v = -Eigen::Vector3d::UnitZ();  // unit, along rows, perpendicular to u
  double pixel_mm = 0.4;
  int width = 512;
  int height = 512;

  Eigen::Vector3d pixel_center_mm(double c, double r) const {
    return center_mm + ((c - 0.5 * (width - 1)) * pixel_mm) * u + ((r - 0.5 * (height - 1)) * pixel_mm) * v;
  }
  // unit normal of the detector plane pointing away from the source
  Eigen::Vector3d normal() const;
  // continuous pixel coordinates (c, r) where the ray from the source through p_mm meets the
  // detector plane; false when p_mm is not in front of the source (the ray never gets there)
  bool project(const Eigen::Vector3d& p_mm, Eigen::Vector2d* cr) const;
};

// the detector of every stride-th pixel of g, each coarse pixel a stride x stride block's: coarse
// pixel (C, R) is centred on g's pixel (s C + (s - 1) / 2, s R + (s - 1) / 2) (the last row and
// column reach past g's edge when its size is not a multiple of s)
DetectorGeometry coarse_detector(const DetectorGeometry& g, int stride);
// rows [first_row, first_row + rows) of g as a detector of their own (a band of the image)
DetectorGeometry detector_rows(const DetectorGeometry& g, int first_row, int rows);

// empty when usable: finite entries, unit and orthogonal u and v, pixel_mm > 0, sizes >= 1,
// and the source off the detector plane; otherwise what is wrong
std::string validate(const DetectorGeometry& g);

}  // namespace pcisim::xray
