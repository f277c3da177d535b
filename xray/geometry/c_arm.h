#pragma once
// A C-arm as DICOM describes it (PS3.3 C.8.7.5, XA Positioner Module): Positioner Primary Angle
// (0018,1510) turns the beam in the patient's transverse plane, 0 = detector above the chest
// (AP), +90 = detector at the patient's left (LAO 90), -90 at the right (RAO 90); Positioner
// Secondary Angle (0018,1511) tilts it in the sagittal plane, +90 = detector toward the head
// (cranial, CRA), negative = caudal (CAU). The angles give the direction from the isocentre to
// the detector in patient LPS: d = (sin a cos b, -cos a cos b, sin b). Details: docs/xray.md.
#include <Eigen/Core>

#include "xray/geometry/detector_geometry.h"

namespace pcisim::xray {

struct CArmSpec {
  double source_to_image_mm = 1100;  // SID: source to detector plane
  double source_to_axis_mm = 750;    // SAD: source to isocentre
  int width = 512, height = 512;     // detector pixels
  double pixel_mm = 0.4;             // detector pixel pitch
};

struct CArmPose {
  double primary_deg = 0;    // LAO positive, RAO negative
  double secondary_deg = 0;  // cranial positive, caudal negative
  // the table position, given as the patient point (LPS, mm) that sits at the isocentre
  Eigen::Vector3d isocenter_mm = Eigen::Vector3d::Zero();
};

// unit vector from the isocentre toward the detector (the central ray's direction)
Eigen::Vector3d c_arm_beam_direction(double primary_deg, double secondary_deg);
// inverse of c_arm_beam_direction: angles (deg) of a unit direction; primary in (-180, 180],
// secondary in [-90, 90] (primary is 0 when the direction is straight up or down)
Eigen::Vector2d c_arm_angles(const Eigen::Vector3d& beam_direction);

// source, detector plane and image axes: columns run toward the patient's left in AP (u =
// (cos a, sin a, 0)), rows run toward the feet (v = u x d), as fluoroscopy is displayed
DetectorGeometry c_arm_geometry(const CArmSpec& spec, const CArmPose& pose);

}  // namespace pcisim::xray
