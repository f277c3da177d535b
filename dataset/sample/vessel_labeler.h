#pragma once
// The contrast-filled vessels of one frame as label images: per pixel the iodine's line integral
// (the sum over lumen segments of mu_iodine x opacity x chord, the same analytic chords the frame
// was rendered with, xray/overlay/tube_overlay.h), the mask where it reaches a threshold, and the
// branch that holds most of it. Buffers sized once per detector size.
#include <cstdint>
#include <vector>

#include "xray/fluoro/contrast_bolus.h"
#include "xray/geometry/detector_geometry.h"
#include "xray/projectors/image.h"

namespace pcisim::dataset {

class VesselLabeler {
 public:
  explicit VesselLabeler(double min_line_integral) : min_line_integral_(min_line_integral) {}

  // from the bolus as the frame's render() left it (segments where they moved, their opacity)
  void label(const xray::DetectorGeometry& g, const xray::ContrastBolus& bolus, double iodine_mu_per_mm);

  // 255 where the iodine's line integral >= min_line_integral, else 0; row-major, row 0 first
  const std::vector<uint8_t>& mask() const { return mask_; }
  // in the mask: 1 + the tree index of the branch with the largest line integral there; else 0
  const std::vector<uint8_t>& branch_ids() const { return branch_ids_; }
  const xray::Image& iodine() const { return total_; }  // the line integral, all branches
  int64_t mask_pixels() const { return mask_pixels_; }

 private:
  double min_line_integral_;
  xray::Image total_, one_, best_;
  std::vector<uint8_t> mask_, branch_ids_;
  int64_t mask_pixels_ = 0;
};

}  // namespace pcisim::dataset
