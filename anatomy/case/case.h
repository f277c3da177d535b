#pragma once
// A patient case: everything a scene's anatomy is, as plain data. The server builds one per scene
// (from a case folder or a phantom seed) and hands the same value to physics, imaging and status.
// Frame: patient LPS (x left, y posterior, z superior). Format on disk: docs/anatomy.md.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "anatomy/heart/heart_pose.h"
#include "anatomy/mesh/triangle_mesh.h"
#include "anatomy/organ/organ.h"
#include "anatomy/vessel/lesion.h"
#include "anatomy/vessel/vessel_tree.h"
#include "anatomy/volume/volume.h"

namespace pcisim::anatomy {

struct Landmark {
  std::string name;
  Eigen::Vector3d position_m;
};

struct Case {
  std::string name;                // for logs and status
  VesselTree vessels;              // centerlines and radii, metres
  std::vector<Lesion> lesions;     // the stenoses of those vessels (lesions.json; none: empty)
  TriangleMesh lumen;              // the lumen surface, metres, closed; empty when the case has none
  std::optional<Volume> ct;        // CT in HU, mm
  bool ct_lumen_enhanced = false;  // the CT's lumens hold contrast (a CT angiogram) rather than blood
  std::vector<Landmark> landmarks;
  HeartPose heart;  // where the template heart sits under these vessels (identity: the phantom's)
  // the template heart's rest vertices fitted to this patient's CT, in the template's frame
  // (metres, over the template's tets: one column per template vertex); empty: the template's own
  Eigen::Matrix3Xd heart_vertices_m;
  // the soft-tissue scene's organ (the CT above is then the organ's); absent in coronary cases
  std::optional<Organ> organ;
};

}  // namespace pcisim::anatomy
