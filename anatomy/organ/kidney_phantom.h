#pragma once
// A procedural kidney-like organ as plain data (issue #16 item 1; soft-tissue paper, "Collision and
// data preparation": the organ the particle model is built from). The shape is star-shaped about
// its centre: a bean = an ellipsoid whose radius toward the medial side (-x) is pulled in by a
// Gaussian hilum indentation. Its surface is the radial map of a latitude-longitude sphere (closed
// and manifold by construction; the marching tetrahedra of vessel/lumen_surface are not needed for
// a star-shaped body). The CT paints every voxel centre by the same classification, so tests
// have exact truth. Organ frame = LPS, centre at the origin, long axis along S.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "anatomy/mesh/triangle_mesh.h"
#include "anatomy/organ/organ.h"
#include "anatomy/volume/volume.h"

namespace pcisim::anatomy {

// Tissue HU (typical values; Radiopaedia "Hounsfield unit"; Buzug, "Computed Tomography", 2008,
// table 1.1): renal cortex ~150 HU is the nephrographic-phase enhanced value; medulla ~30; renal
// pelvis filled with urine ~10; a solid tumour ~60; fat ~-100; a metal-bright bead 2000 (clamped);
// the support table is an assumed plastic/carbon top of 200 HU.
constexpr double kKidneyCortexHu = 150.0;
constexpr double kKidneyMedullaHu = 30.0;
constexpr double kKidneyPelvisHu = 10.0;
// the renal sinus's fat (a little denser than the perirenal: vessels and lymphatics run in it);
// the renal vein and artery at the hilum, contrast-enhanced (nephrographic phase: the vein ~160,
// the artery ~200 HU)
constexpr double kKidneySinusFatHu = -80.0;
constexpr double kKidneyVeinHu = 160.0;
constexpr double kKidneyArteryHu = 200.0;
constexpr double kKidneyTumourHu = 60.0;
constexpr double kKidneyFatHu = -100.0;
constexpr double kKidneyBeadHu = 2000.0;
constexpr double kKidneyTableHu = 200.0;
constexpr double kKidneyAirHu = -1000.0;

struct KidneySpec {
  Eigen::Vector3d semi_axes_mm{30.0, 17.5, 55.0};  // L x P x S: 60 x 35 x 110 mm
  double hilum_depth = 0.4;                        // fraction of the radius removed at the hilum's centre
  double hilum_width_rad = 0.45;                   // Gaussian width (angle from -x) of the indentation
  // the organ's inside (issue #32; Standring, Gray's Anatomy 41st ed., ch. 74: a cortex 7-10 mm
  // thick with columns between 8-18 medullary pyramids whose papillae point into the renal sinus,
  // where minor calyces cup them and drain through infundibula into the pelvis, in the sinus's
  // fat; the renal vein anterior to the artery at the hilum). Directions and cones are taken in
  // the organ's normalised frame (p / semi_axes: the ellipsoid a unit sphere).
  double cortex_mm = 7.0;                // the cortex's depth below the surface
  double sinus_fraction = 0.35;          // normalised radius s below which the renal sinus is
  double pyramid_half_angle_deg = 17.0;  // each pyramid's half-angle at its base
  double calyx_radius_mm = 2.5;          // a minor calyx cupping each papilla, its centre half a
                                         // radius inside the sinus along the pyramid's axis
  double infundibulum_radius_mm = 1.3;   // calyx -> pelvis
  Eigen::Vector3d pelvis_centre_mm{-10.0, 0.0, 0.0};
  Eigen::Vector3d pelvis_semi_axes_mm{8.0, 4.5, 11.0};
  double vein_radius_mm = 4.0;    // along -x from the sinus, anterior (y = -vein_offset)
  double artery_radius_mm = 2.5;  // along -x, posterior (y = +artery_offset)
  double vein_offset_mm = 4.5;
  double artery_offset_mm = 3.5;
  double tumour_radius_mm = 7.5;  // 15 mm diameter
  int fiducial_count = 45;
  double bead_radius_mm = 1.0;
  double fiducial_min_gap_mm = 7.0;  // beads at least this far apart (spread through the organ)
  double ct_spacing_mm = 1.0;
  double ct_margin_mm = 12.0;        // fat around the organ's box
  double table_gap_mm = 5.0;         // fat between the organ's posterior extent and the table top
  double table_thickness_mm = 10.0;  // the table is a slab along +y (posterior: patient supine)
  int surface_rings = 60;            // latitude rings of the surface (poles along S)
  int surface_segments = 96;         // longitude segments
  uint64_t seed = 1;                 // varies tumour and bead placement
};

// what was drawn, exactly
struct KidneyFacts {
  Eigen::Vector3d tumour_centre_mm = Eigen::Vector3d::Zero();
  double tumour_radius_mm = 0.0;
  std::vector<Eigen::Vector3d> fiducials_mm;  // bead centres, all inside the organ
  double table_top_y_mm = 0.0;                // table occupies y in [top, top + thickness]
  double table_bottom_y_mm = 0.0;
  double implicit_volume_mm3 = 0.0;  // volume of the implicit shape (quadrature of r^3/3 over the sphere)
};

// kMedulla: a pyramid; kPelvis: urine (the pelvis, a calyx or an infundibulum)
enum class KidneyTissue { kAir, kFat, kTable, kCortex, kMedulla, kPelvis, kSinusFat, kVein, kArtery, kTumour, kBead };
double kidney_tissue_hu(KidneyTissue t);
// each tissue's name, in the enum's order (a label's name in the tissue map; the ultrasound's
// acoustic table knows each: ultrasound/echo/tissue_acoustics.h)
const std::vector<std::string>& kidney_tissue_names();

struct KidneyPhantom {
  KidneySpec spec;
  KidneyFacts facts;
  TriangleMesh surface;  // metres, LPS, closed, counter-clockwise seen from outside
  Volume ct;             // HU, int16
  Volume tissue;         // the KidneyTissue at each CT voxel's centre (int16 labels, the CT's grid)
};

// the organ's radius toward unit direction d (mm)
double kidney_radius_mm(const KidneySpec& spec, const Eigen::Vector3d& d);
// normalised radius s = |p| / r(p/|p|): s < 1 inside, s > 1 outside
double kidney_normalised_radius(const KidneySpec& spec, const Eigen::Vector3d& p_mm);
// the pyramids' axes: unit directions in the organ's normalised frame: an anterior (-y) and a
// posterior (+y) row at four heights along the long axis (latitudes -50, -20, 20, 50 degrees),
// three along the lateral border (+x; -30, 0, 30) and one near each pole (80 degrees), none toward
// the hilum: 13 pyramids
const std::vector<Eigen::Vector3d>& kidney_pyramid_axes();
// the renal sinus's boundary (normalised radius) along p's direction: sinus_fraction, rising to
// the surface at the hilum, where the sinus opens (a Gaussian in the angle from -x of 0.6 times
// the hilum's width): s_sinus = f + (1 - f) exp(-alpha^2 / (2 (0.6 w)^2))
double kidney_sinus_fraction(const KidneySpec& spec, const Eigen::Vector3d& p_mm);
// what the CT paints at p (beads, tumour, the organ's inside, vessels, table, fat)
KidneyTissue kidney_tissue_at(const KidneySpec& spec, const KidneyFacts& facts, const Eigen::Vector3d& p_mm);

// throws std::invalid_argument on a spec that cannot be drawn (non-positive sizes, too many beads)
KidneyPhantom make_kidney_phantom(const KidneySpec& spec = {});

// the phantom as the soft-tissue scene's organ: its surface, beads (metres), its support (the
// plane touching its posterior surface; supine: posterior is +y, down, so the plane faces -y) and
// its tissue map
Organ kidney_organ(const KidneyPhantom& phantom);

}  // namespace pcisim::anatomy
