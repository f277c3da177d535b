#pragma once
// Stage (b) of the CTA pipeline (docs/modeling.md): from the coarse lumen, keep the aorta and the
// coronary trees connected to it; cut away chambers and everything else the contrast region
// reached. The paper did this by hand. The rule here, automatic:
//  1. the "large" lumen is the morphological opening of the region by a ball of big_radius_mm
//     (voxels within big_radius_mm of a voxel whose distance to the region's edge is at least
//     big_radius_mm), grown by rim_mm inside the region so that the noisy edge of the aorta and
//     the chambers goes with them: the aorta, the chambers and their connections; no coronary
//     artery is that wide (a left main is at most ~5.5 mm across);
//  2. what is left are thin structures; each 26-connected piece of them is a coronary tree when it
//     touches the large lumen (its ostium: of several contact patches, the deepest, where the
//     trunk enters the root; a chamber it runs beside or a rim is shallow), reaches at least
//     min_length_mm from there (trabeculae, noise and a blurred edge do not), is somewhere at least min_piece_radius_mm
//     from its own edge (a sheet of edge voxels is not), is slender (its volume over its reach no more than a tube of
//     max_tree_tube_radius_mm: a chamber whose contrast sits at the threshold becomes a sponge of noise, thin
//     everywhere but filling its space, and is not) and its ostium lies within max_ostium_distance_mm of the aortic
//     seed (the coronary ostia sit in the aortic root; pieces on a ventricle or an atrium are farther). A piece holding
//     a further seed is kept whatever the rule says.
//  3. the aorta's centerline runs from the ostia's level through the seed and up the ascending
//     aorta along the ridge of the distance map.
#include <string>
#include <vector>
#include "anatomy/vessel/vessel_tree.h"
#include "modeling/cta/lumen_segmentation.h"

namespace pcisim::modeling {

struct ClippingOptions {
  double big_radius_mm = 3.0;
  double rim_mm = 1.0;               // the large lumen also takes this much of its own rough edge
  double min_piece_radius_mm = 0.6;  // a piece nowhere this far from its edge is a rim or a sheet, not a vessel
  double min_length_mm = 15.0;
  double max_tree_tube_radius_mm = 5.0;
  double max_ostium_distance_mm = 70.0;
  double aorta_above_seed_mm = 30.0;  // how far the aortic centerline goes on past the seed
  // no piece qualifying is a ModelingError; false: an empty `pieces` and the error's message in
  // `none_found` (the pipeline then may fill again: cta_pipeline.h)
  bool throw_when_none = true;
  int threads = 0;
};

struct CoronaryPiece {
  std::vector<int64_t> voxels;  // crop indices
  int64_t ostium = -1;          // the piece's voxel at the middle of its contact with the large lumen
  double reach_mm = 0;          // farthest voxel from the ostium
  Eigen::Vector3d ostium_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d aortic_centre_mm = Eigen::Vector3d::Zero();  // the aorta's centre beside the ostium
};

struct Clipping {
  FloatImage distance_mm;             // each lumen voxel's distance to the lumen's edge (crop grid)
  Mask large;                         // the opening: aorta, chambers
  std::vector<CoronaryPiece> pieces;  // kept, largest reach first
  std::vector<std::string> dropped;   // why each other thin piece was cut away (pieces of >= 50 voxels)
  // sponges attached within max_ostium_distance_mm of the seed: pieces cut away as a chamber's
  // noisy contrast where a coronary tree leaves the aortic root (it may be in one)
  int root_sponges = 0;
  std::string none_found;  // with throw_when_none false and no piece kept: why
  anatomy::CenterlinePoint aorta_at_seed;
  std::vector<anatomy::CenterlinePoint> aorta;  // proximal (root) to distal (up the ascending aorta), mm
};

// throws ModelingError when no piece qualifies (a CTA without visible coronaries; unless
// throw_when_none is false)
Clipping clip_to_coronaries(const LumenSegmentation& seg, const std::vector<Eigen::Vector3d>& seeds_mm,
                            const ClippingOptions& options);

}  // namespace pcisim::modeling
