#include "xray/projectors/ray_packet.h"

#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <cmath>

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

// Joseph's method for eight rays on the planes of one axis (ray_march.h: slice_ray), all on the
// same plane at each step: plane j_first + k sign, lane i at (base_b + k step_b, base_c + k
// step_c) in it. Four bilinear reads a sample. Where the plane's other axis b is the grid's rows
// (axis y or z) and the eight points lie within 8 voxels along b and 2 along c, the reads are
// whole rows loaded once and spread to the lanes by permutes (slice_packet_counts: nearly every
// step of pcisim-bench xray's view); else they are gathered
__attribute__((target("avx2,fma"))) void slice_march_x8(const GridView& g, int axis, int sign, int j_first,
                                                        const float (&base)[2][8], const float (&step)[2][8], int k_max,
                                                        const uint8_t* active, float sum[8], int64_t* row_steps,
                                                        int64_t* gathered_steps) {
  const int b = axis == 0 ? 1 : 0, c = axis == 2 ? 1 : 2;
  const int n[3] = {g.nx, g.ny, g.nz};
  const int stride[3] = {1, g.nx, g.nx * g.ny};  // < 2^31: the caller checks the padded count
  const int64_t total = int64_t(g.nx) * g.ny * g.nz;
  const bool rows = b == 0;  // the plane's b axis is contiguous in memory
  const __m256 bb = _mm256_load_ps(base[0]), bc = _mm256_load_ps(base[1]);
  const __m256 sb = _mm256_load_ps(step[0]), sc = _mm256_load_ps(step[1]);
  const __m256i max_b = _mm256_set1_epi32(n[b] - 2), max_c = _mm256_set1_epi32(n[c] - 2);
  const __m256i stride_b = _mm256_set1_epi32(stride[b]), stride_c = _mm256_set1_epi32(stride[c]);
  const __m256i zero_i = _mm256_setzero_si256();
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.f);
  const __m256i lane_bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const float* mu = g.mu;
  const int ob = stride[b], oc = stride[c];
  __m256 acc = zero;
  for (int k = 0; k < k_max; ++k) {
    const int bits = active[k];
    if (!bits) continue;
    int ia = j_first + k * sign;
    ia = ia < 0 ? 0 : (ia > n[axis] - 1 ? n[axis] - 1 : ia);
    const __m256 kf = _mm256_set1_ps(static_cast<float>(k));
    const __m256 pb = _mm256_fmadd_ps(kf, sb, bb), pc = _mm256_fmadd_ps(kf, sc, bc);
    __m256i ib = _mm256_cvttps_epi32(pb), ic = _mm256_cvttps_epi32(pc);
    ib = _mm256_min_epi32(_mm256_max_epi32(ib, zero_i), max_b);
    ic = _mm256_min_epi32(_mm256_max_epi32(ic, zero_i), max_c);
    const __m256 fb = _mm256_min_ps(_mm256_max_ps(_mm256_sub_ps(pb, _mm256_cvtepi32_ps(ib)), zero), one);
    const __m256 fc = _mm256_min_ps(_mm256_max_ps(_mm256_sub_ps(pc, _mm256_cvtepi32_ps(ic)), zero), one);
    __m256 p00, p10, p01, p11;
    int b_lo = 0, c_lo = 0;
    bool loaded = false;
    if (rows) {
      // the end lanes bound the rest (the points of a row of pixels lie in order along it),
      // checked: an offset outside 0..7, or a row outside c_lo..c_lo + 1, takes the gathers
      const int b0 = _mm256_cvtsi256_si32(ib), b7 = _mm256_extract_epi32(ib, 7);
      const int c0 = _mm256_cvtsi256_si32(ic), c7 = _mm256_extract_epi32(ic, 7);
      b_lo = b0 < b7 ? b0 : b7;
      c_lo = c0 < c7 ? c0 : c7;
      const __m256i off_b = _mm256_sub_epi32(ib, _mm256_set1_epi32(b_lo));
      const __m256i off_c = _mm256_sub_epi32(ic, _mm256_set1_epi32(c_lo));
      const __m256i out_of = _mm256_or_si256(
          _mm256_or_si256(_mm256_cmpgt_epi32(off_b, _mm256_set1_epi32(7)), _mm256_cmpgt_epi32(zero_i, off_b)),
          _mm256_or_si256(_mm256_cmpgt_epi32(off_c, _mm256_set1_epi32(1)), _mm256_cmpgt_epi32(zero_i, off_c)));
      const int64_t at = int64_t(ia) * stride[axis] + int64_t(c_lo) * oc + b_lo;
      if (_mm256_testz_si256(out_of, out_of) && at + 2 * int64_t(oc) + 9 <= total) {
        // rows c_lo, c_lo + 1 (and c_lo + 2 for lanes one row further), voxels b_lo .. b_lo + 8
        const float* row0 = mu + at;
        const __m256i off = off_b;
        p00 = _mm256_permutevar8x32_ps(_mm256_loadu_ps(row0), off);
        p10 = _mm256_permutevar8x32_ps(_mm256_loadu_ps(row0 + 1), off);
        p01 = _mm256_permutevar8x32_ps(_mm256_loadu_ps(row0 + oc), off);
        p11 = _mm256_permutevar8x32_ps(_mm256_loadu_ps(row0 + oc + 1), off);
        if (!_mm256_testz_si256(off_c, off_c)) {
          const __m256 up = _mm256_castsi256_ps(_mm256_cmpgt_epi32(off_c, zero_i));
          const __m256 q01 = _mm256_permutevar8x32_ps(_mm256_loadu_ps(row0 + 2 * oc), off);
          const __m256 q11 = _mm256_permutevar8x32_ps(_mm256_loadu_ps(row0 + 2 * oc + 1), off);
          p00 = _mm256_blendv_ps(p00, p01, up);
          p10 = _mm256_blendv_ps(p10, p11, up);
          p01 = _mm256_blendv_ps(p01, q01, up);
          p11 = _mm256_blendv_ps(p11, q11, up);
        }
        loaded = true;
        ++*row_steps;
      }
    }
    if (!loaded) {
      ++*gathered_steps;
      const __m256i at =
          _mm256_add_epi32(_mm256_set1_epi32(ia * stride[axis]),
                           _mm256_add_epi32(_mm256_mullo_epi32(ib, stride_b), _mm256_mullo_epi32(ic, stride_c)));
      p00 = _mm256_i32gather_ps(mu, at, 4);
      p10 = _mm256_i32gather_ps(mu + ob, at, 4);
      p01 = _mm256_i32gather_ps(mu + oc, at, 4);
      p11 = _mm256_i32gather_ps(mu + ob + oc, at, 4);
    }
    const __m256 c0 = _mm256_fmadd_ps(fb, _mm256_sub_ps(p10, p00), p00);
    const __m256 c1 = _mm256_fmadd_ps(fb, _mm256_sub_ps(p11, p01), p01);
    const __m256 v = _mm256_fmadd_ps(fc, _mm256_sub_ps(c1, c0), c0);
    const __m256i on = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(bits), lane_bit), lane_bit);
    acc = _mm256_add_ps(acc, _mm256_and_ps(v, _mm256_castsi256_ps(on)));
  }
  _mm256_storeu_ps(sum, acc);
}

}  // namespace

namespace {
std::atomic<int64_t> counts_row_steps{0}, counts_gathered_steps{0}, counts_shared_walks{0}, counts_lane_walks{0};
}  // namespace

SlicePacketCounts slice_packet_counts() {
  return {counts_row_steps.load(std::memory_order_relaxed), counts_gathered_steps.load(std::memory_order_relaxed),
          counts_shared_walks.load(std::memory_order_relaxed), counts_lane_walks.load(std::memory_order_relaxed)};
}

void slice_rays_x8(const GridView& g, const DetectorView& d, int c0, int r, bool skip_empty, float out[8]) {
  // the packet's axis: its middle ray's major one; a lane whose own major axis is another (a
  // packet across a 45-degree diagonal) is marched alone on it, so every ray takes the planes
  // slice_ray takes
  RaySetup s[8];
  bool hit[8];
  int mid = -1;
  for (int i = 0; i < 8; ++i) {
    hit[i] = setup_ray(g, d, c0 + i, r, 1.0f, &s[i]);
    if (hit[i] && (mid < 0 || i == 4)) mid = i;
  }
  for (int i = 0; i < 8; ++i) out[i] = 0.f;
  if (mid < 0) return;
  const int axis = major_axis(s[mid].dx);
  const int sign = s[mid].dx[axis] > 0.f ? 1 : -1;
  const int b = axis == 0 ? 1 : 0, c = axis == 2 ? 1 : 2;
  // marched: the lanes the packet samples (the others give 0, or slice_ray's answer when alone)
  bool alone[8] = {}, marched[8] = {};
  int j0[8] = {};
  bool any = false;
  int j_first = 0;
  for (int i = 0; i < 8; ++i) {
    if (!hit[i]) continue;
    alone[i] = major_axis(s[i].dx) != axis || !(s[i].dx[axis] * sign > 0.f);
    marched[i] = !alone[i] && to_planes(axis, &s[i], &j0[i]);
    if (!marched[i]) continue;
    j_first = !any ? j0[i] : (sign > 0 ? std::min(j_first, j0[i]) : std::max(j_first, j0[i]));
    any = true;
  }
  // every lane on plane j_first + k sign at step k: lane i's own sample k' is step k' + o_i
  alignas(32) float base[2][8], step[2][8];
  int k_max = 0, o[8] = {};
  for (int i = 0; i < 8; ++i) {
    if (!marched[i]) continue;
    o[i] = (j0[i] - j_first) * sign;
    k_max = std::max(k_max, s[i].k_end + o[i]);
  }
  if (any && k_max <= kPacketMaxSamples && packet_supported()) {
    int ref = -1;  // a marched lane, whose path the others stand on (masked out)
    for (int i = 0; i < 8 && ref < 0; ++i)
      if (marched[i]) ref = i;
    for (int i = 0; i < 8; ++i) {
      const int l = marched[i] ? i : ref;
      const float t = (static_cast<float>(j_first) - s[l].x0[axis]) / s[l].dx[axis];  // on plane j_first
      base[0][i] = s[l].x0[b] + t * s[l].dx[b];
      base[1][i] = s[l].x0[c] + t * s[l].dx[c];
      step[0][i] = s[l].dt * s[l].dx[b];
      step[1][i] = s[l].dt * s[l].dx[c];
    }
    // which lanes take each step. Where every lane stays within a brick of the middle one (at the
    // first and last steps: positions are linear between; a voxel short of it, for the rounding
    // between the walk's crossings and the stepped positions), one walk of the middle ray over the
    // bricks near mu (AttenuationVolume::brick_near) covers every brick the others meet that holds
    // mu, and they sample there and within their own range: a superset of their own runs, whose
    // extra samples read only zeros and add exactly nothing. Else each lane walks its own bricks
    uint8_t active[kPacketMaxSamples];
    std::fill(active, active + k_max, uint8_t(0));
    bool shared = skip_empty && g.brick_near != nullptr && marched[mid];
    for (int i = 0; i < 8 && shared; ++i) {
      if (!marched[i]) continue;
      for (const int k : {0, k_max - 1})
        for (int e = 0; e < 2; ++e)
          if (!(fabsf((base[e][i] - base[e][mid]) + k * (step[e][i] - step[e][mid])) < float(g.brick - 1)))
            shared = false;
    }
    if (shared) {
      for (int i = 0; i < 8; ++i) {
        if (!marched[i]) continue;
        const uint8_t bit = static_cast<uint8_t>(1u << i);
        for (int k = o[i]; k < o[i] + s[i].k_end; ++k) active[k] |= bit;
      }
      // outside the middle ray's own steps every lane samples; inside, only along its near runs
      uint8_t keep[kPacketMaxSamples];
      std::fill(keep, keep + k_max, uint8_t(0xff));
      const int m_lo = o[mid], m_hi = o[mid] + s[mid].k_end;
      std::fill(keep + m_lo, keep + m_hi, uint8_t(0));
      auto near_run = [&](int lo, int hi) { std::fill(keep + m_lo + lo, keep + m_lo + hi, uint8_t(0xff)); };
      auto near_mu = [&](int x, int y, int z) { return g.brick_near[x + g.bnx * (y + int64_t(g.bny) * z)] != 0; };
      for_each_run_where(g, s[mid], near_mu, near_run);
      for (int k = 0; k < k_max; ++k) active[k] &= keep[k];
    } else {
      for (int i = 0; i < 8; ++i) {
        if (!marched[i]) continue;
        const uint8_t bit = static_cast<uint8_t>(1u << i);
        uint8_t* lane = active + o[i];
        auto run = [&](int lo, int hi) {
          for (int k = lo; k < hi; ++k) lane[k] |= bit;
        };
        for_each_run(g, s[i], skip_empty, run);
      }
    }
    float sum[8];
    int64_t rows = 0, gathered = 0;
    slice_march_x8(g, axis, sign, j_first, base, step, k_max, active, sum, &rows, &gathered);
    counts_row_steps.fetch_add(rows, std::memory_order_relaxed);
    counts_gathered_steps.fetch_add(gathered, std::memory_order_relaxed);
    (shared ? counts_shared_walks : counts_lane_walks).fetch_add(1, std::memory_order_relaxed);
    for (int i = 0; i < 8; ++i)
      if (marched[i]) out[i] = sum[i] * s[i].dt * s[i].len_mm;
  } else {
    for (int i = 0; i < 8; ++i)
      if (marched[i]) out[i] = slice_ray(g, d, c0 + i, r, skip_empty);
  }
  for (int i = 0; i < 8; ++i)
    if (alone[i]) out[i] = slice_ray(g, d, c0 + i, r, skip_empty);
}

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
