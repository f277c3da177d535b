#include "anatomy/organ/organ.h"

#include <fmt/format.h>

#include <cmath>

namespace pcisim::anatomy {

std::string validate_tissue_map(const TissueMap& map, const Volume& ct) {
  if (map.names.empty()) return "names: empty (one name per label, label 0 first)";
  for (size_t i = 0; i < map.names.size(); ++i)
    if (map.names[i].empty()) return fmt::format("names[{}]: empty", i);
  if (const std::string bad = validate(map.labels); !bad.empty()) return "labels: " + bad;
  if (map.labels.type != VoxelType::kInt16)
    return fmt::format("labels: {} voxels (a label volume is int16)", voxel_type_name(map.labels.type));
  if (map.labels.dims != ct.dims)
    return fmt::format("labels: {} x {} x {} voxels, the CT has {} x {} x {} (a label volume is on the CT's grid)",
                       map.labels.dims[0], map.labels.dims[1], map.labels.dims[2], ct.dims[0], ct.dims[1], ct.dims[2]);
  // the grids agree to a thousandth of a voxel (files keep the numbers to ~1e-6 mm)
  const double tol = 1e-3 * ct.spacing_mm.minCoeff();
  if ((map.labels.spacing_mm - ct.spacing_mm).cwiseAbs().maxCoeff() > tol ||
      (map.labels.origin_mm - ct.origin_mm).cwiseAbs().maxCoeff() > tol ||
      (map.labels.direction - ct.direction).cwiseAbs().maxCoeff() > 1e-6)
    return "labels: spacing, origin or direction differ from the CT's (a label volume is on the CT's grid)";
  const auto count = static_cast<int64_t>(map.names.size());
  for (int64_t n = 0; n < map.labels.voxel_count(); ++n) {
    const int16_t v = map.labels.hu_i16[n];
    if (v < 0 || v >= count) {
      const int64_t i = n % ct.dims[0], j = n / ct.dims[0] % ct.dims[1], k = n / (ct.dims[0] * ct.dims[1]);
      return fmt::format("labels: voxel ({}, {}, {}) holds {}, not a label of the {} names (0 to {})", i, j, k, v,
                         count, count - 1);
    }
  }
  return "";
}

}  // namespace pcisim::anatomy
