#pragma once
// The image chain of a fluoroscopy frame after the line integrals: Beer-Lambert with N0 quanta
// per pixel, Poisson quantum noise, detector blur (separable Gaussian, after the noise as in a
// scintillator), log, and a display window mapped to uint16 with radiopaque structures dark.
// All buffers are sized once per detector size; apply() allocates nothing after that.
#include <cstdint>
#include <vector>

#include "xray/projectors/image.h"

namespace pcisim::xray {

struct DetectorChainSpec {
  double photons_per_pixel = 2000;  // N0; 0: noiseless (and I = exp(-L))
  double blur_sigma_px = 0.7;       // 0: none
};

class DetectorChain {
 public:
  explicit DetectorChain(const DetectorChainSpec& spec);

  // display window in line-integral units: lo maps to white (65535), hi to black (0)
  void set_window(double lo, double hi) {
    lo_ = lo;
    hi_ = hi;
  }
  double window_lo() const { return lo_; }
  double window_hi() const { return hi_; }

  // subtracted from the log image before the window (dynamic range compression); nullptr: none.
  // The image must outlive the chain's use and have the frame's size.
  void set_offset(const Image* offset) { offset_ = offset; }

  // line integrals -> counts (noise from noise_key, blur) -> display; counts is kept for tests
  void apply(const Image& line, uint64_t noise_key, Image* counts, std::vector<uint16_t>* display);

 private:
  DetectorChainSpec spec_;
  std::vector<float> kernel_;  // half of the symmetric Gaussian, [0] the centre
  Image tmp_;
  double lo_ = 0, hi_ = 1;
  const Image* offset_ = nullptr;
};

// the display's dynamic range compression (as cath-lab image processors do, a.k.a. harmonisation):
// offset = strength x (the image box-filtered twice over radius_px, minus its mean), so large
// slow variations (heart over spine vs lung) shrink and small dense detail keeps its contrast.
// tmp and offset are resized to the image when needed.
void range_compression_offset(const Image& line, int radius_px, double strength, Image* tmp, Image* offset);

// a window for a background of line integrals: from its 1st percentile to its 99.5th plus 15 %
// of the range, so iodine and wire over the densest anatomy still darken; scratch is reused
void display_window_for(const Image& background, std::vector<float>* scratch, double* lo, double* hi);

// Poisson(lambda) from one uniform u in [0, 1): exact inversion below 30 quanta, the normal
// approximation lambda + sqrt(lambda) z above (z from the second uniform by Box-Muller)
double poisson_sample(double lambda, double u1, double u2);

}  // namespace pcisim::xray
