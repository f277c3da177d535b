#include "xray/fluoro/case_background.h"

#include <algorithm>
#include <cmath>

#include "anatomy/phantom/thorax_phantom.h"

namespace pcisim::xray {
namespace {

// squared distance from p to the segment ab
double segment_distance2(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).squaredNorm();
}

}  // namespace

int64_t fill_lumens_with_blood(anatomy::Volume& ct, const anatomy::VesselTree& tree, double blood_hu) {
  int64_t changed = 0;
  for (const auto& branch : tree.branches) {
    for (size_t i = 0; i + 1 < branch.points.size(); ++i) {
      const Eigen::Vector3d a = branch.points[i].position_m * 1e3, b = branch.points[i + 1].position_m * 1e3;
      const double r = std::max(branch.points[i].radius_m, branch.points[i + 1].radius_m) * 1e3;
      // the segment's box in index space, over every corner of its bounding box (oblique grids)
      Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
      for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d corner((c & 1 ? a.cwiseMax(b).x() + r : a.cwiseMin(b).x() - r),
                                     (c & 2 ? a.cwiseMax(b).y() + r : a.cwiseMin(b).y() - r),
                                     (c & 4 ? a.cwiseMax(b).z() + r : a.cwiseMin(b).z() - r));
        const Eigen::Vector3d ijk = ct.physical_to_index(corner);
        lo = lo.cwiseMin(ijk);
        hi = hi.cwiseMax(ijk);
      }
      int64_t from[3], to[3];
      for (int k = 0; k < 3; ++k) {
        from[k] = std::max<int64_t>(0, static_cast<int64_t>(std::floor(lo[k])));
        to[k] = std::min<int64_t>(ct.dims[k] - 1, static_cast<int64_t>(std::ceil(hi[k])));
      }
      for (int64_t z = from[2]; z <= to[2]; ++z)
        for (int64_t y = from[1]; y <= to[1]; ++y)
          for (int64_t x = from[0]; x <= to[0]; ++x) {
            const Eigen::Vector3d p = ct.index_to_physical_mm(Eigen::Vector3d(x, y, z));
            if (segment_distance2(p, a, b) > r * r) continue;
            const int64_t n = ct.linear_index(x, y, z);
            if (ct.type == anatomy::VoxelType::kInt16) {
              if (ct.hu_i16[n] > blood_hu) ct.hu_i16[n] = static_cast<int16_t>(blood_hu), ++changed;
            } else if (ct.hu_f32[n] > blood_hu) {
              ct.hu_f32[n] = static_cast<float>(blood_hu), ++changed;
            }
          }
    }
  }
  return changed;
}

anatomy::Volume background_volume(const anatomy::Case& c, const FluoroSpec& spec) {
  if (c.ct) {
    anatomy::Volume ct = *c.ct;
    if (c.ct_lumen_enhanced) fill_lumens_with_blood(ct, c.vessels, anatomy::ThoraxTissueHu{}.blood);
    return ct;
  }
  return thorax_background(c.vessels, spec);
}

anatomy::Volume thorax_background(const anatomy::VesselTree& tree, const FluoroSpec& spec) {
  anatomy::ThoraxPhantomSpec p;
  p.seed = spec.seed;
  p.dims = spec.volume_dims;
  p.spacing_mm = spec.volume_spacing_mm;
  p.contrast = false;  // blood-filled lumens: the iodine comes per frame, analytically
  return anatomy::make_thorax_phantom(p, tree);
}

}  // namespace pcisim::xray
