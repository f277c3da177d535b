#pragma once
// COCO-style annotations (the object-detection format of Lin et al., ECCV 2014, as pycocotools
// reads it), so common ML tooling reads a pcisim dataset without pcisim: one "guidewire"
// annotation per frame with keypoints along its distal span (tip last), one "vessel" annotation
// per contrast-filled branch with its mask as uncompressed RLE. COCO coordinates put (0, 0) at the
// first pixel's top-left corner: x = c + 0.5, y = r + 0.5 of the labels' pixel-centre (c, r).
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace pcisim::dataset {

// the categories (ids 1 guidewire, 2 vessel) with `keypoints` named k00.. and the last "tip"
nlohmann::json coco_categories(int keypoints);

// uncompressed RLE of the pixels of `labels` equal to `value`: column-major runs, the first a run
// of pixels not in the region (possibly 0), as pycocotools' frPyObjects reads it (the vessel
// annotations below are written by the same run builder)
nlohmann::json coco_rle(std::span<const uint8_t> labels, int width, int height, uint8_t value, int64_t* area,
                        std::array<int, 4>* bbox);

// one frame's annotations (image_id and ids left 0: numbered when the dataset is merged).
// keypoints as wire_keypoints() gives them; branch_ids as VesselLabeler gives them
nlohmann::json coco_frame_annotations(std::span<const Eigen::Vector3d> keypoints, std::span<const uint8_t> branch_ids,
                                      int width, int height, const std::vector<std::string>& branch_names);

}  // namespace pcisim::dataset
