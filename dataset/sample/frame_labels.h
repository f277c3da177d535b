#pragma once
// A frame's ground truth as JSON (docs/dataset.md defines every field): the projection (its 3x4
// matrix and the detector it comes from), the C-arm, the wire in 3-D and on the image with its tip
// and COCO keypoints, and every centerline in 3-D and on the image with its branch label.
// Pixel convention: (c, r) with (0, 0) the centre of the first pixel of the first row.
#include <Eigen/Core>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "anatomy/vessel/vessel_tree.h"
#include "xray/geometry/c_arm.h"
#include "xray/geometry/detector_geometry.h"

namespace pcisim::dataset {

// P (3x4) with (c w, r w, w) = P (x, y, z, 1) for a point x in mm (the case's LPS frame); w > 0 in
// front of the source. The same map as DetectorGeometry::project
Eigen::Matrix<double, 3, 4> projection_matrix(const xray::DetectorGeometry& g);

// `count` points along the wire's distal `span_mm` (by 3-D arc length, evenly, the tip last),
// projected: (c, r, v) with v = 2 inside the image, 0 outside or behind the source. Fewer nodes
// than the span: from the first node. No nodes: empty
std::vector<Eigen::Vector3d> wire_keypoints(const xray::DetectorGeometry& g, std::span<const Eigen::Vector3d> wire_mm,
                                            int count, double span_mm);

struct FrameTruth {
  int frame = 0;
  double time_s = 0, heart_phase = 0;
  xray::DetectorGeometry geometry;
  xray::CArmPose pose;
  double sid_mm = 0, sad_mm = 0;
  std::span<const Eigen::Vector3d> wire_mm;    // proximal to distal
  std::span<const Eigen::Vector2d> wire_px;    // as the renderer projected them
  std::span<const Eigen::Vector3d> keypoints;  // wire_keypoints()
  std::string tip_branch;                      // "" when unknown
  const anatomy::VesselTree* tree = nullptr;
  std::span<const Eigen::Vector3d> vessel_points_mm;  // tree order; empty: the tree at rest
  std::span<const double> branch_opacity;             // by tree index (the bolus's)
  std::span<const double> point_opacity;              // by centerline point, tree order (0..1)
  double visible_opacity = 0.05;                      // a branch holds visible contrast above this
  int64_t mask_pixels = 0;
};

nlohmann::json frame_labels(const FrameTruth& t);

}  // namespace pcisim::dataset
