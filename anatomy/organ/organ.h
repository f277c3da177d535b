#pragma once
// An organ for the soft-tissue scene as plain data (issue #16): its closed surface, the fiducial
// beads inside it and the support it rests on. The case's CT (Case::ct) is the organ's CT.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "anatomy/mesh/triangle_mesh.h"
#include "anatomy/volume/volume.h"

namespace pcisim::anatomy {

// what tissue each voxel of the case's CT holds (issue #32): the ultrasound takes each tissue's
// acoustic properties from its name (ultrasound/echo/tissue_acoustics.h) rather than guessing
// them from HU. labels: int16 on the CT's grid, each an index into names (a 3D Slicer labelmap)
struct TissueMap {
  Volume labels;
  std::vector<std::string> names;
};

// empty when the map fits the CT (same grid, int16, every label an index into non-empty names),
// otherwise what is wrong
std::string validate_tissue_map(const TissueMap& map, const Volume& ct);

struct Organ {
  std::string name;
  TriangleMesh surface;                      // metres, closed, counter-clockwise seen from outside
  std::vector<Eigen::Vector3d> fiducials_m;  // bead centres
  // the support's top plane: free side where support_normal . x >= support_offset_m (normal unit,
  // pointing out of the support toward the organ)
  Eigen::Vector3d support_normal = -Eigen::Vector3d::UnitY();
  double support_offset_m = 0.0;
  // the tissue of each CT voxel (case folder: tissue.nrrd); absent: the ultrasound maps HU
  std::optional<TissueMap> tissue;
};

}  // namespace pcisim::anatomy
