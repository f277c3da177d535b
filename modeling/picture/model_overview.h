#pragma once
// The picture beside every model pcisim-model builds (overview.png): three maximum-intensity
// projections of the CT, front (patient left on the image's right, head up), side (anterior on
// the left, head up) and from the feet (anterior up, patient left on the right).
#include <Eigen/Core>
#include <string>
#include <vector>
#include "anatomy/vessel/vessel_tree.h"
#include "anatomy/volume/volume.h"

namespace pcisim::modeling {

// a model scored against truth: its false centerline (red) and the truth it missed (yellow),
// points in the CT's frame, mm
struct OverviewMarks {
  std::vector<Eigen::Vector3d> false_mm, missed_mm;
};

// a branch named by the anatomy (labelled), not generically after its parent ("D1-2")
bool is_named_branch(const std::string& name);

// throws std::runtime_error when the file cannot be written
void write_model_overview(const anatomy::Volume& ct, const anatomy::VesselTree& tree, const std::string& title,
                          const std::string& png_path, const OverviewMarks* marks = nullptr);

}  // namespace pcisim::modeling
