#include "dataset/sample/vessel_labeler.h"

#include <algorithm>
#include <array>
#include <stdexcept>

#include "xray/overlay/tube_overlay.h"

namespace pcisim::dataset {

using xray::kMinDrawnOpacity;

void VesselLabeler::label(const xray::DetectorGeometry& g, const xray::ContrastBolus& bolus, double iodine_mu_per_mm) {
  const size_t n = static_cast<size_t>(g.width) * g.height;
  if (total_.width != g.width || total_.height != g.height) {
    total_.resize(g.width, g.height);
    one_.resize(g.width, g.height);
    best_.resize(g.width, g.height);
    mask_.assign(n, 0);
    branch_ids_.assign(n, 0);
  }
  const auto& segs = bolus.segments();
  const auto& op = bolus.segment_opacity();
  const size_t branches = bolus.branch_opacity().size();
  if (branches > 254) throw std::length_error("VesselLabeler: more than 254 branches do not fit an 8-bit label image");
  std::fill(total_.pixels.begin(), total_.pixels.end(), 0.0f);
  std::fill(best_.pixels.begin(), best_.pixels.end(), 0.0f);
  std::fill(branch_ids_.begin(), branch_ids_.end(), 0);
  // branch by branch: its own line integral (in one_, zero outside the box being worked on),
  // added to the total, and the largest wins the pixel; only the branch's shadow box is visited
  for (size_t b = 0; b < branches; ++b) {
    if (bolus.branch_opacity()[b] < kMinDrawnOpacity) continue;
    int c0 = g.width, c1 = -1, r0 = g.height, r1 = -1;
    for (size_t i = 0; i < segs.size(); ++i) {
      if (segs[i].branch != static_cast<int>(b) || op[i] < kMinDrawnOpacity) continue;
      std::array<int, 4> box;
      if (!xray::cone_shadow_box(g, segs[i].a_mm, segs[i].b_mm, segs[i].ra_mm, segs[i].rb_mm, &box)) continue;
      xray::add_cone_segment(g, segs[i].a_mm, segs[i].b_mm, segs[i].ra_mm, segs[i].rb_mm, iodine_mu_per_mm * op[i],
                             &one_);
      c0 = std::min(c0, box[0]), c1 = std::max(c1, box[1]), r0 = std::min(r0, box[2]), r1 = std::max(r1, box[3]);
    }
    const auto id = static_cast<uint8_t>(b + 1);
    for (int r = r0; r <= r1; ++r) {
      float* row = one_.pixels.data() + static_cast<size_t>(r) * g.width;
      for (int c = c0; c <= c1; ++c) {
        const float x = row[c];
        if (x <= 0.0f) continue;
        row[c] = 0.0f;  // one_ is all zero again for the next branch
        const size_t p = static_cast<size_t>(r) * g.width + c;
        total_.pixels[p] += x;
        if (x > best_.pixels[p]) {
          best_.pixels[p] = x;
          branch_ids_[p] = id;
        }
      }
    }
  }
  mask_pixels_ = 0;
  for (size_t p = 0; p < n; ++p) {
    const bool in = total_.pixels[p] >= min_line_integral_;
    mask_[p] = in ? 255 : 0;
    if (!in) branch_ids_[p] = 0;
    mask_pixels_ += in;
  }
}

}  // namespace pcisim::dataset
