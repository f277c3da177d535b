#include "dataset/sample/coco.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace pcisim::dataset {
namespace {

// uncompressed RLE of a region given as its pixels' column-major indices (c * height + r), sorted:
// runs alternate outside / inside, the first outside (possibly 0); its area and box too
nlohmann::json rle_of_sorted(const std::vector<int64_t>& idx, int width, int height, int64_t* area,
                             std::array<int, 4>* bbox) {
  std::vector<int64_t> counts;
  int64_t next = 0;  // the first pixel not yet counted
  int c0 = width, r0 = height, c1 = -1, r1 = -1;
  for (size_t k = 0; k < idx.size();) {
    size_t e = k + 1;  // a run of consecutive indices
    while (e < idx.size() && idx[e] == idx[e - 1] + 1) ++e;
    counts.push_back(idx[k] - next);
    counts.push_back(static_cast<int64_t>(e - k));
    next = idx[e - 1] + 1;
    for (size_t j = k; j < e; ++j) {
      const int c = static_cast<int>(idx[j] / height), r = static_cast<int>(idx[j] % height);
      c0 = std::min(c0, c), c1 = std::max(c1, c), r0 = std::min(r0, r), r1 = std::max(r1, r);
    }
    k = e;
  }
  const int64_t n = static_cast<int64_t>(width) * height;
  if (next < n || counts.empty()) counts.push_back(n - next);
  *area = static_cast<int64_t>(idx.size());
  *bbox = idx.empty() ? std::array<int, 4>{0, 0, 0, 0} : std::array<int, 4>{c0, r0, c1 - c0 + 1, r1 - r0 + 1};
  return {{"counts", counts}, {"size", {height, width}}};
}

}  // namespace

nlohmann::json coco_categories(int keypoints) {
  nlohmann::json names = nlohmann::json::array(), skeleton = nlohmann::json::array();
  for (int k = 0; k < keypoints; ++k)
    names.push_back(k + 1 == keypoints ? std::string("tip") : fmt::format("k{:02d}", k));
  for (int k = 1; k < keypoints; ++k) skeleton.push_back({k, k + 1});  // 1-based, consecutive points
  return nlohmann::json::array({
      {{"id", 1}, {"name", "guidewire"}, {"supercategory", "device"}, {"keypoints", names}, {"skeleton", skeleton}},
      {{"id", 2}, {"name", "vessel"}, {"supercategory", "anatomy"}},
  });
}

nlohmann::json coco_rle(std::span<const uint8_t> labels, int width, int height, uint8_t value, int64_t* area,
                        std::array<int, 4>* bbox) {
  std::vector<int64_t> idx;
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c)
      if (labels[static_cast<size_t>(r) * width + c] == value) idx.push_back(static_cast<int64_t>(c) * height + r);
  std::sort(idx.begin(), idx.end());
  return rle_of_sorted(idx, width, height, area, bbox);
}

nlohmann::json coco_frame_annotations(std::span<const Eigen::Vector3d> keypoints, std::span<const uint8_t> branch_ids,
                                      int width, int height, const std::vector<std::string>& branch_names) {
  nlohmann::json out = nlohmann::json::array();
  // the wire: its keypoints (0, 0, 0 where not visible) and the box around the visible ones
  nlohmann::json flat = nlohmann::json::array();
  int visible = 0;
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (const auto& k : keypoints) {
    if (k.z() > 0) {
      const double x = k.x() + 0.5, y = k.y() + 0.5;
      flat.push_back(x), flat.push_back(y), flat.push_back(2);
      x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
      ++visible;
    } else {
      flat.push_back(0), flat.push_back(0), flat.push_back(0);
    }
  }
  if (visible > 0) {
    // the box grown by a pixel each way: a straight wire along a row still has an area
    x0 = std::max(0.0, x0 - 1), y0 = std::max(0.0, y0 - 1);
    x1 = std::min(static_cast<double>(width), x1 + 1), y1 = std::min(static_cast<double>(height), y1 + 1);
    out.push_back({{"id", 0},
                   {"image_id", 0},
                   {"category_id", 1},
                   {"keypoints", flat},
                   {"num_keypoints", visible},
                   {"bbox", {x0, y0, x1 - x0, y1 - y0}},
                   {"area", (x1 - x0) * (y1 - y0)},
                   {"iscrowd", 0}});
  }
  // the vessels: one annotation per branch present in the label image. One row-major pass
  // gathers every labelled pixel's column-major index per branch (the image is mostly 0), then
  // each branch's runs, area and box come from its sorted indices
  std::vector<std::vector<int64_t>> at(256);
  for (int r = 0; r < height; ++r) {
    const uint8_t* row = branch_ids.data() + static_cast<size_t>(r) * width;
    for (int c = 0; c < width; ++c)
      if (row[c] != 0) at[row[c]].push_back(static_cast<int64_t>(c) * height + r);
  }
  for (int id = 1; id < 256; ++id) {
    std::vector<int64_t>& idx = at[static_cast<size_t>(id)];
    if (idx.empty()) continue;
    std::sort(idx.begin(), idx.end());
    int64_t area = 0;
    std::array<int, 4> box{};
    nlohmann::json rle = rle_of_sorted(idx, width, height, &area, &box);
    out.push_back({{"id", 0},
                   {"image_id", 0},
                   {"category_id", 2},
                   {"segmentation", std::move(rle)},
                   {"area", area},
                   {"bbox", box},
                   {"iscrowd", 0},
                   {"branch", static_cast<size_t>(id - 1) < branch_names.size() ? branch_names[id - 1] : ""}});
  }
  return out;
}

}  // namespace pcisim::dataset
