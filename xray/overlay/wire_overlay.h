#pragma once
// The guidewire in a frame: its attenuation added to a DRR analytically (a chain of thin metal
// cylinders along the wire's polyline), and its 2D polyline on the detector for ground-truth
// labels. Nothing allocates once the output vector has its capacity.
#include <Eigen/Core>
#include <vector>

#include "xray/geometry/detector_geometry.h"
#include "xray/projectors/image.h"

namespace pcisim::xray {

struct WireSpec {
  double radius_mm = 0.1778;  // a 0.014" coronary guidewire
  // stainless steel near 60 keV: mu/rho of iron ~1.2 cm^2/g (NIST XCOM / Hubbell & Seltzer
  // tables) times 7.9 g/cm^3 ~ 0.95 /mm; a platinum tip coil attenuates several times more
  double mu_per_mm = 0.95;
};

// adds mu * chord for every ray (source -> pixel centre) through every segment's cylinder
// (no end caps, so joints are neither doubled nor, for a gently bending wire, visibly gapped);
// only the pixels near each segment's shadow are visited
void add_wire(const DetectorGeometry& g, const std::vector<Eigen::Vector3d>& wire_mm, const WireSpec& wire,
              Image* image);

// pixel coordinates (c, r) of each wire point; points behind the source come out as NaN
void project_polyline(const DetectorGeometry& g, const std::vector<Eigen::Vector3d>& points_mm,
                      std::vector<Eigen::Vector2d>* pixels);

}  // namespace pcisim::xray
