#pragma once
// The template heart's closed surfaces (a piecewise-linear complex for TetGen): the epicardium
// (ventricles on the phantom's 50 mm sphere, atria as bulges at the base) and the LV and RV
// cavities as holes. Built in the heart frame (heart_frame.h), written in patient LPS millimetres.
#include <Eigen/Core>
#include <array>
#include <iosfwd>
#include <vector>

namespace pcisim::anatomy {

// boundary markers carried through TetGen into the .face file
enum HeartSurfaceMarker : int { kEpicardium = 1, kLvEndocardium = 2, kRvEndocardium = 3 };

struct HeartSurface {
  std::vector<Eigen::Vector3d> vertices_mm;   // patient LPS
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise seen from the tissue's outside
  std::vector<int> markers;                   // one HeartSurfaceMarker per triangle
  std::vector<Eigen::Vector3d> holes_mm;      // one point inside each cavity
};

// epicardial radius (mm) along a unit direction given in the heart frame
double epicardial_radius_mm(const Eigen::Vector3d& heart_dir);

// LV and RV cavities at end-diastole, heart frame (mm): centre, semi-axes along the frame's
// axes after rotating about e3 by azimuth_rad (x' radial, y' tangential, z' = e3)
struct CavityEllipsoid {
  Eigen::Vector3d centre_mm;
  Eigen::Vector3d semi_axes_mm;
  double azimuth_rad = 0.0;
};
CavityEllipsoid lv_cavity();
CavityEllipsoid rv_cavity();

HeartSurface template_heart_surface();

// TetGen .poly (part 1 nodes, part 2 facets with markers, part 3 holes, part 4 no regions)
void write_tetgen_poly(const HeartSurface& surface, std::ostream& out);

}  // namespace pcisim::anatomy
