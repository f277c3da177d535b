#include "xray/projectors/ray_packet.h"

#include <immintrin.h>

#include <algorithm>

namespace pcisim::xray::ray {

bool packet_supported() {
  static const bool yes = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return yes;
}

namespace {

// the packet's kernel, compiled for AVX2 + FMA only (the caller checks packet_supported())
__attribute__((target("avx2,fma"))) void march_x8(const GridView& g, const RaySetup (&s)[8], int k_max,
                                                  const uint8_t* active, float out[8]) {
  // lane constants: x(k) = base + k step, base = x0 + (t0 + dt / 2) dx, step = dt dx
  alignas(32) float base[3][8], step[3][8];
  for (int i = 0; i < 8; ++i) {
    const bool hit = s[i].k_end > 0;
    const float tb = hit ? s[i].t0 + 0.5f * s[i].dt : 0.f;
    for (int a = 0; a < 3; ++a) {
      base[a][i] = hit ? s[i].x0[a] + tb * s[i].dx[a] : 0.f;
      step[a][i] = hit ? s[i].dt * s[i].dx[a] : 0.f;
    }
  }
  const __m256 bx = _mm256_load_ps(base[0]), by = _mm256_load_ps(base[1]), bz = _mm256_load_ps(base[2]);
  const __m256 sx = _mm256_load_ps(step[0]), sy = _mm256_load_ps(step[1]), sz = _mm256_load_ps(step[2]);
  const __m256i max_x = _mm256_set1_epi32(g.nx - 2), max_y = _mm256_set1_epi32(g.ny - 2),
                max_z = _mm256_set1_epi32(g.nz - 2);
  const __m256i zero_i = _mm256_setzero_si256();
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.f);
  const int row = g.nx, slice = g.nx * g.ny;  // < 2^31: padded grids up to ~1290^3
  const __m256i row_v = _mm256_set1_epi32(row), slice_v = _mm256_set1_epi32(slice);
  const __m256i lane_bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const float* mu = g.mu;
  __m256 acc = zero;
  for (int k = 0; k < k_max; ++k) {
    const int bits = active[k];
    if (!bits) continue;
    // the same read as trilinear(): truncation for floor, indices and fractions clamped
    const __m256 kf = _mm256_set1_ps(static_cast<float>(k));
    const __m256 x = _mm256_fmadd_ps(kf, sx, bx), y = _mm256_fmadd_ps(kf, sy, by), z = _mm256_fmadd_ps(kf, sz, bz);
    __m256i ix = _mm256_cvttps_epi32(x), iy = _mm256_cvttps_epi32(y), iz = _mm256_cvttps_epi32(z);
    ix = _mm256_min_epi32(_mm256_max_epi32(ix, zero_i), max_x);
    iy = _mm256_min_epi32(_mm256_max_epi32(iy, zero_i), max_y);
    iz = _mm256_min_epi32(_mm256_max_epi32(iz, zero_i), max_z);
    const __m256 fx = _mm256_min_ps(_mm256_max_ps(_mm256_sub_ps(x, _mm256_cvtepi32_ps(ix)), zero), one);
    const __m256 fy = _mm256_min_ps(_mm256_max_ps(_mm256_sub_ps(y, _mm256_cvtepi32_ps(iy)), zero), one);
    const __m256 fz = _mm256_min_ps(_mm256_max_ps(_mm256_sub_ps(z, _mm256_cvtepi32_ps(iz)), zero), one);
    const __m256i at =
        _mm256_add_epi32(ix, _mm256_add_epi32(_mm256_mullo_epi32(iy, row_v), _mm256_mullo_epi32(iz, slice_v)));
    const __m256 p000 = _mm256_i32gather_ps(mu, at, 4), p100 = _mm256_i32gather_ps(mu + 1, at, 4);
    const __m256 p010 = _mm256_i32gather_ps(mu + row, at, 4), p110 = _mm256_i32gather_ps(mu + row + 1, at, 4);
    const __m256 p001 = _mm256_i32gather_ps(mu + slice, at, 4), p101 = _mm256_i32gather_ps(mu + slice + 1, at, 4);
    const __m256 p011 = _mm256_i32gather_ps(mu + slice + row, at, 4);
    const __m256 p111 = _mm256_i32gather_ps(mu + slice + row + 1, at, 4);
    const __m256 c00 = _mm256_fmadd_ps(fx, _mm256_sub_ps(p100, p000), p000);
    const __m256 c10 = _mm256_fmadd_ps(fx, _mm256_sub_ps(p110, p010), p010);
    const __m256 c01 = _mm256_fmadd_ps(fx, _mm256_sub_ps(p101, p001), p001);
    const __m256 c11 = _mm256_fmadd_ps(fx, _mm256_sub_ps(p111, p011), p011);
    const __m256 c0 = _mm256_fmadd_ps(fy, _mm256_sub_ps(c10, c00), c00);
    const __m256 c1 = _mm256_fmadd_ps(fy, _mm256_sub_ps(c11, c01), c01);
    const __m256 v = _mm256_fmadd_ps(fz, _mm256_sub_ps(c1, c0), c0);
    // only the lanes whose ray takes sample k add it
    const __m256i on = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(bits), lane_bit), lane_bit);
    acc = _mm256_add_ps(acc, _mm256_and_ps(v, _mm256_castsi256_ps(on)));
  }
  alignas(32) float sum[8];
  _mm256_store_ps(sum, acc);
  for (int i = 0; i < 8; ++i) out[i] = s[i].k_end > 0 ? sum[i] * s[i].dt * s[i].len_mm : 0.f;
}

}  // namespace

void trilinear_rays_x8(const GridView& g, const DetectorView& d, int c0, int r, float step_voxels, bool skip_empty,
                       float out[8]) {
  RaySetup s[8];
  int k_max = 0;
  for (int i = 0; i < 8; ++i) {
    setup_ray(g, d, c0 + i, r, step_voxels, &s[i]);
    k_max = std::max(k_max, s[i].k_end);
  }
  if (k_max > kPacketMaxSamples || !packet_supported()) {
    for (int i = 0; i < 8; ++i) out[i] = trilinear_ray(g, d, c0 + i, r, step_voxels, skip_empty);
    return;
  }
  // which lanes take each sample: lane i's bit over its runs
  uint8_t active[kPacketMaxSamples];
  std::fill(active, active + k_max, uint8_t(0));
  for (int i = 0; i < 8; ++i) {
    const uint8_t bit = static_cast<uint8_t>(1u << i);
    auto run = [&](int lo, int hi) {
      for (int k = lo; k < hi; ++k) active[k] |= bit;
    };
    for_each_run(g, s[i], skip_empty, run);
  }
  march_x8(g, s, k_max, active, out);
}

}  // namespace pcisim::xray::ray
