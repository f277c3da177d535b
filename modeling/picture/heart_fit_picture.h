#pragma once
// The picture beside a fitted heart (heart-fit.png): three slices of the CT through the heart's
// centre (coronal, sagittal, axial; oriented as overview.png's views), soft-tissue window, with the
// template's epicardium cut by each plane as placed (red) and as fitted to the CT (green).
#include <Eigen/Core>
#include <string>

#include "anatomy/heart/heart_mesh.h"
#include "anatomy/heart/heart_pose.h"
#include "anatomy/volume/volume.h"

namespace pcisim::modeling {

// `placed_m` and `fitted_m`: the mesh's vertices in the template's frame (metres), carried into
// the CT by `pose`. Throws std::runtime_error when the file cannot be written
void write_heart_fit_picture(const anatomy::Volume& ct, const anatomy::HeartMesh& mesh, const anatomy::HeartPose& pose,
                             const Eigen::Matrix3Xd& placed_m, const Eigen::Matrix3Xd& fitted_m,
                             const std::string& title, const std::string& png_path);

}  // namespace pcisim::modeling
