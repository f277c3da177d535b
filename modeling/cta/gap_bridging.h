#pragma once
// Between stages (a) and (b) of the CTA pipeline (docs/modeling.md): a tight stenosis or an
// occlusion leaves no lumen the CT resolves, so the contrast region grown from the seeds stops
// there and the vessel beyond it is lost. Here each piece of contrast HU that the region did not
// reach is joined to it when
//  - it is a vessel: at least min_length_mm long along its main axis and no wider than
//    max_radius_mm (its volume over pi times its length), so chambers and noise are not, and
//    under max_bright_shell of its outer neighbours are brighter than lumen (the marrow of a rib
//    or a vertebra sits inside cortical bone, a vessel in fat or muscle) and its voxels have on
//    average at least min_mean_neighbours of their 26 neighbours in it and at least
//    min_interior_fraction of them have all six face neighbours in it (a lumen is solid; noise
//    above the threshold in tissue just below it strings together through corners and edges);
//  - its nearest point lies within max_gap_mm of the region;
//  - the region ends there, as a thin vessel: within end_ball_mm of that end the region fills
//    under max_end_fill of the ball (the aorta's or a chamber's wall fills half), and its voxels
//    there lie behind the end, within max_angle_deg of the line across the gap; the piece starts
//    there the same way, on the far side;
//  - it holds the same contrast: the 90th percentile over its voxels of the mean HU of their 3x3x3
//    neighbourhoods within a factor min_contrast_ratio of that over the region's voxels within
//    end_ball_mm of the end (costal cartilage at ~150 HU, whose noise crosses the threshold, and a
//    vein are darker; the blurred rim of a rib beside its cortex is brighter).
// The gap is filled by a thin cylinder (bridge_radius_mm), the piece is added, and each bridge is
// reported: a stenosis too tight to see, or an occlusion, at that place. The line across the gap
// is straight; the radius measured there later (stage d) is the narrow one the CT shows.
#include <Eigen/Core>
#include <vector>
#include "anatomy/volume/volume.h"
#include "modeling/image/image3.h"

namespace pcisim::modeling {

struct GapBridgingOptions {
  bool enabled = true;
  double max_gap_mm = 10.0;
  double min_length_mm = 10.0;
  double max_radius_mm = 3.0;
  double max_bright_shell = 0.05;
  double min_mean_neighbours = 8;
  double min_interior_fraction = 0.05;
  double end_ball_mm = 5.0;
  double max_end_fill = 0.3;
  double max_angle_deg = 40.0;
  double min_contrast_ratio = 0.75;
  double bridge_radius_mm = 0.5;
  int passes = 2;  // a piece joined in one pass may bring the next one within reach
};

struct Bridge {
  Eigen::Vector3d from_mm = Eigen::Vector3d::Zero();  // the region's end (CT physical frame)
  Eigen::Vector3d to_mm = Eigen::Vector3d::Zero();    // the piece's start
  double gap_mm = 0;
  double piece_length_mm = 0;  // the joined piece's extent along its main axis
  int64_t voxels_added = 0;    // the piece's and the bridge's
};

// adds the bridged pieces (voxels of HU in [lower_hu, upper_hu] outside the region) to `region`,
// a mask on the CT's whole grid; returns the bridges, in the order they were made. Memory: the
// pieces' voxel lists and the search around each piece (no image-sized buffer besides `region`).
std::vector<Bridge> bridge_gaps(const anatomy::Volume& ct, double lower_hu, double upper_hu, Mask* region,
                                const GapBridgingOptions& options);

}  // namespace pcisim::modeling
