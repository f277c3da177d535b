#include "xray/fluoro/detector_chain.h"

#include <span>

#include "realtime/percentile.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pcisim::xray {
namespace {

// splitmix64 finaliser (Steele, Lea & Flood, "Fast splittable pseudorandom number generators",
// OOPSLA 2014): a counter hashed per pixel, so the noise is a pure function of key and pixel
uint64_t mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}
double uniform01(uint64_t h) {
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

}  // namespace

double poisson_sample(double lambda, double u1, double u2) {
  if (!(lambda > 0)) return 0.0;
  if (lambda < 30) {
    // inversion: walk the CDF from k = 0 (~lambda steps)
    double p = std::exp(-lambda), cdf = p;
    int k = 0;
    while (u1 > cdf && k < 200) {
      ++k;
      p *= lambda / k;
      cdf += p;
    }
    return k;
  }
  const double z = std::sqrt(-2.0 * std::log(std::max(u1, 1e-300))) * std::cos(2.0 * std::numbers::pi * u2);
  return std::max(0.0, lambda + std::sqrt(lambda) * z);
}

DetectorChain::DetectorChain(const DetectorChainSpec& spec) : spec_(spec) {
  if (spec_.blur_sigma_px > 0) {
    const int radius = std::max(1, static_cast<int>(std::ceil(3.0 * spec_.blur_sigma_px)));
    kernel_.resize(radius + 1);
    double sum = 0;
    for (int i = 0; i <= radius; ++i) {
      kernel_[i] = static_cast<float>(std::exp(-0.5 * i * i / (spec_.blur_sigma_px * spec_.blur_sigma_px)));
      sum += (i == 0 ? 1.0 : 2.0) * kernel_[i];
    }
    for (float& k : kernel_) k = static_cast<float>(k / sum);
  }
}

void DetectorChain::apply(const Image& line, uint64_t noise_key, Image* counts, std::vector<uint16_t>* display) {
  const int w = line.width, h = line.height;
  const size_t n = static_cast<size_t>(w) * h;
  if (counts->width != w || counts->height != h) counts->resize(w, h);
  if (display->size() != n) display->resize(n);
  const double n0 = spec_.photons_per_pixel > 0 ? spec_.photons_per_pixel : 1.0;
  const float* l = line.pixels.data();
  float* q = counts->pixels.data();
  if (spec_.photons_per_pixel > 0) {
    const uint64_t key = mix64(noise_key);
    for (size_t i = 0; i < n; ++i) {
      const double lambda = n0 * std::exp(-static_cast<double>(l[i]));
      const uint64_t hsh = mix64(key ^ (i * 0xd1b54a32d192ed03ull));
      q[i] = static_cast<float>(poisson_sample(lambda, uniform01(hsh), uniform01(mix64(hsh))));
    }
  } else {
    for (size_t i = 0; i < n; ++i) q[i] = std::exp(-l[i]);
  }
  // separable blur, edges clamped
  if (!kernel_.empty()) {
    if (tmp_.width != w || tmp_.height != h) tmp_.resize(w, h);
    const int rad = static_cast<int>(kernel_.size()) - 1;
    const float* k = kernel_.data();
    for (int r = 0; r < h; ++r) {  // along rows into tmp
      const float* src = q + static_cast<size_t>(r) * w;
      float* dst = tmp_.pixels.data() + static_cast<size_t>(r) * w;
      for (int c = 0; c < w; ++c) {
        float acc = k[0] * src[c];
        if (c >= rad && c + rad < w) {
          for (int i = 1; i <= rad; ++i) acc += k[i] * (src[c - i] + src[c + i]);
        } else {
          for (int i = 1; i <= rad; ++i) acc += k[i] * (src[std::max(c - i, 0)] + src[std::min(c + i, w - 1)]);
        }
        dst[c] = acc;
      }
    }
    for (int r = 0; r < h; ++r) {  // along columns back into counts
      float* dst = q + static_cast<size_t>(r) * w;
      const float* mid = tmp_.pixels.data() + static_cast<size_t>(r) * w;
      for (int c = 0; c < w; ++c) dst[c] = k[0] * mid[c];
      for (int i = 1; i <= rad; ++i) {
        const float* up = tmp_.pixels.data() + static_cast<size_t>(std::max(r - i, 0)) * w;
        const float* dn = tmp_.pixels.data() + static_cast<size_t>(std::min(r + i, h - 1)) * w;
        for (int c = 0; c < w; ++c) dst[c] += k[i] * (up[c] + dn[c]);
      }
    }
  }
  // log (half a quantum keeps empty pixels finite) and the window, dark = attenuating
  const float inv_n0 = static_cast<float>(1.0 / n0);
  const float lo = static_cast<float>(lo_);
  const float scale = static_cast<float>(65535.0 / std::max(hi_ - lo_, 1e-9));
  const float floor_q = spec_.photons_per_pixel > 0 ? 0.5f : 1e-30f;
  uint16_t* out = display->data();
  const bool offset = offset_ && offset_->width == w && offset_->height == h;
  const float* off = offset ? offset_->pixels.data() : nullptr;
  for (size_t i = 0; i < n; ++i) {
    float lm = -std::log(std::max(q[i], floor_q) * inv_n0);
    if (off) lm -= off[i];
    const float v = 65535.0f - (lm - lo) * scale;
    // a non-finite line integral shows black (v NaN would pass std::clamp and break the cast)
    out[i] = std::isfinite(v) ? static_cast<uint16_t>(std::clamp(v, 0.0f, 65535.0f) + 0.5f) : uint16_t{0};
  }
}

namespace {
// running-sum box filter of radius r along rows (stride 1) or columns (stride w), edges clamped
void box_pass(const float* src, float* dst, int n_lines, int len, int line_stride, int step, int r) {
  const float inv = 1.0f / (2 * r + 1);
  for (int l = 0; l < n_lines; ++l) {
    const float* s = src + static_cast<size_t>(l) * line_stride;
    float* d = dst + static_cast<size_t>(l) * line_stride;
    auto at = [&](int i) { return s[static_cast<size_t>(std::clamp(i, 0, len - 1)) * step]; };
    double acc = 0;
    for (int i = -r; i <= r; ++i) acc += at(i);
    for (int i = 0; i < len; ++i) {
      d[static_cast<size_t>(i) * step] = static_cast<float>(acc * inv);
      acc += at(i + r + 1) - at(i - r);
    }
  }
}
}  // namespace

void range_compression_offset(const Image& line, int radius_px, double strength, Image* tmp, Image* offset) {
  const int w = line.width, h = line.height;
  if (tmp->width != w || tmp->height != h) tmp->resize(w, h);
  if (offset->width != w || offset->height != h) offset->resize(w, h);
  if (!(strength > 0) || radius_px < 1 || w == 0 || h == 0) {
    std::fill(offset->pixels.begin(), offset->pixels.end(), 0.0f);
    return;
  }
  // two box passes each way ~ a Gaussian of sigma ~ 0.8 radius
  box_pass(line.pixels.data(), tmp->pixels.data(), h, w, w, 1, radius_px);
  box_pass(tmp->pixels.data(), offset->pixels.data(), w, h, 1, w, radius_px);
  box_pass(offset->pixels.data(), tmp->pixels.data(), h, w, w, 1, radius_px);
  box_pass(tmp->pixels.data(), offset->pixels.data(), w, h, 1, w, radius_px);
  double mean = 0;
  for (float v : offset->pixels) mean += v;
  mean /= offset->pixels.size();
  for (float& v : offset->pixels) v = static_cast<float>(strength * (v - mean));
}

void display_window_for(const Image& background, std::vector<float>* scratch, double* lo, double* hi) {
  scratch->assign(background.pixels.begin(), background.pixels.end());
  if (scratch->empty()) {
    *lo = 0;
    *hi = 1;
    return;
  }
  const double a = realtime::percentile_in_place(std::span<float>(*scratch), 0.01);
  const double b = realtime::percentile_in_place(std::span<float>(*scratch), 0.995);
  *lo = a;
  *hi = b + 0.15 * std::max(b - a, 1e-6);
}

}  // namespace pcisim::xray
