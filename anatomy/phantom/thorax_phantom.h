#pragma once
// A procedural thorax CT in Hounsfield units, built around the procedural coronary tree so that
// the DRR, the wire and the lumen mesh all agree: body wall and fat, lungs, liver dome, spine,
// ribs and sternum, heart (myocardium, chambers, pericardial fat), aorta with arch and descending
// part, and the coronary lumens rasterised from the tree's centerlines and radii.
// Frame: patient LPS in mm, heart centre at the origin (the tree's frame scaled by 1000).
// The CT angiogram phantom (phantom_cta.h) uses the same painter with a posed heart, enhanced
// chambers and aorta, an LV outflow tract, and its own coronary lumens.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>

#include "anatomy/vessel/vessel_tree.h"
#include "anatomy/volume/volume.h"

namespace pcisim::anatomy {

// tissue values (HU). Typical ranges: fat -120..-90, soft tissue and muscle +35..+55, unenhanced
// blood +30..+45, aerated lung -900..-700, cancellous bone +300..+400, cortical bone +700..+1900,
// iodinated lumen in coronary CT angiography +300..+450. Sources: T. M. Buzug, Computed
// Tomography (Springer 2008), table 1.1; Radiopaedia, "Hounsfield unit"; SCCT guidelines on
// coronary CT angiography contrast enhancement (Abbara et al., J Cardiovasc Comput Tomogr 2016).
struct ThoraxTissueHu {
  double air = -1000, fat = -100, soft_tissue = 40, muscle = 45, liver = 55, lung = -800;
  double myocardium = 40, blood = 45, cartilage = 150;
  double cancellous_bone = 400, cortical_bone = 900, rib = 700, sternum = 600;
  double csf = 10, disc = 80;
};

// the heart's myocardium is painted as a sphere of this radius (times heart_scale) about the heart
// centre; the coronary tree's epicardial shell sits 1.5 mm above it (docs/anatomy.md)
constexpr double kPhantomHeartRadiusMm = 50.0;

struct ThoraxPhantomSpec {
  uint32_t seed = 1;  // also seeds the coronary tree
  std::array<int64_t, 3> dims{512, 512, 256};
  double spacing_mm = 0.7;  // isotropic
  // per-axis spacing (x, y, z); when finite it replaces spacing_mm
  Eigen::Vector3d spacing_xyz_mm = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  bool contrast = true;      // coronary lumens iodine-filled (else blood)
  double contrast_hu = 400;  // 300..450 for a selective injection
  ThoraxTissueHu hu;
  int threads = 0;  // 0: std::thread::hardware_concurrency()
  // volume centre (mm); NaN: the thorax default, 20 mm above the heart centre
  Eigen::Vector3d center_mm = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());

  // the heart's pose about its centre (the origin): the pericardium, myocardium and chambers are
  // rotated and scaled so; the tree passed in is expected to carry the same pose
  Eigen::Matrix3d heart_rotation = Eigen::Matrix3d::Identity();
  double heart_scale = 1.0;
  // the heart's shape: every length along the heart frame's axes (anterior, left, base) scaled by
  // these on top of heart_scale, chambers and clearances included ((1, 1, 1): the sphere)
  Eigen::Vector3d heart_axes_scale = Eigen::Vector3d::Ones();
  // the right ventricle's cavity: semi-axes in the heart frame (mm, before the scales; NaN: 11, 24,
  // 28) and how far its blood stays inside the myocardium's outer surface, i.e. its free wall (mm;
  // NaN: chamber_clearance_mm)
  Eigen::Vector3d rv_semi_mm = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double rv_wall_mm = std::numeric_limits<double>::quiet_NaN();
  // blood of each chamber and of the aorta (HU); NaN: hu.blood (unenhanced)
  double lv_hu = std::numeric_limits<double>::quiet_NaN();
  double la_hu = std::numeric_limits<double>::quiet_NaN();
  double rv_hu = std::numeric_limits<double>::quiet_NaN();
  double ra_hu = std::numeric_limits<double>::quiet_NaN();
  double aorta_hu = std::numeric_limits<double>::quiet_NaN();
  // the LV outflow tract: a tube of lv_hu blood from the aortic root's proximal end to the LV
  // cavity's centre (radius lv_outflow_radius_mm; 0: 0.75 x the aortic radius), so the aortic
  // lumen and the LV cavity are one connected region as in real anatomy
  bool lv_outflow = false;
  double lv_outflow_radius_mm = 0.0;
  // false: no coronary lumens (a painter of its own draws them over the volume)
  bool coronary_lumens = true;
  // > 0: an epicardial fat sleeve (hu.fat) of this thickness around every coronary branch,
  // painted before the lumens, the aorta and the outflow tract
  double coronary_fat_sleeve_mm = 0.0;
  // > 0: every chamber's blood kept this far inside the myocardium's outer surface (0: the
  // ellipsoids as they are, reaching the surface where the coronaries run)
  double chamber_clearance_mm = 0.0;
};

// builds the coronary tree from spec.seed, then the volume (int16 HU, identity direction).
// The volume is centred on the thorax, 20 mm above the heart centre, at any dims/spacing.
Volume make_thorax_phantom(const ThoraxPhantomSpec& spec);
// the same around a given tree (positions in metres, LPS, heart centre at origin)
Volume make_thorax_phantom(const ThoraxPhantomSpec& spec, const VesselTree& tree);

}  // namespace pcisim::anatomy
