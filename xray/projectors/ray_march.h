#pragma once
// Ray code shared by the CPU projectors and the CUDA kernel (so the CPU trilinear marcher is the
// GPU's twin by construction): plain structs, no Eigen, no allocation, __host__ __device__.
#include <cmath>
#include <cstdint>

#if defined(__CUDACC__)
#define PCISIM_XRAY_HD __host__ __device__ __forceinline__
#else
#define PCISIM_XRAY_HD inline
#endif

namespace pcisim::xray::ray {

// a padded attenuation grid (see AttenuationVolume) and the affine from physical mm to padded
// voxel coordinates: x = m[0..2].p + m[3], y = m[4..6].p + m[7], z = m[8..10].p + m[11]
struct GridView {
  const float* mu = nullptr;
  int nx = 0, ny = 0, nz = 0;  // padded dims
  float m[12] = {};
  const float* brick_max = nullptr;
  const uint8_t* brick_near = nullptr;  // CPU only (AttenuationVolume::brick_near)
  int bnx = 0, bny = 0, bnz = 0;
  int brick = 8;
};

// a detector as plain floats (DetectorGeometry converted once per frame)
struct DetectorView {
  float src[3], center[3], u[3], v[3];
  float pixel_mm;
  int width, height;
};

// [ta, tb] of q0 + t dq inside the box [0, n] per axis, intersected with the input [ta, tb];
// false when empty
template <class T>
PCISIM_XRAY_HD bool clip_to_box(const T q0[3], const T dq[3], const T n[3], T* ta, T* tb) {
  for (int a = 0; a < 3; ++a) {
    if (dq[a] == T(0)) {
      if (q0[a] < T(0) || q0[a] > n[a]) return false;
      continue;
    }
    const T inv = T(1) / dq[a];
    T t0 = (T(0) - q0[a]) * inv, t1 = (n[a] - q0[a]) * inv;
    if (t0 > t1) {
      const T s = t0;
      t0 = t1;
      t1 = s;
    }
    if (t0 > *ta) *ta = t0;
    if (t1 < *tb) *tb = t1;
  }
  return *ta < *tb;
}

// visits the unit cells of a grid of n cells per axis that q0 + t dq crosses for t in [ta, tb]
// (already clipped to the grid box), in order: visit(i, j, k, t_enter, t_exit). A visit that
// returns false stops the walk. (Amanatides & Woo 1987; Siddon 1985, Jacobs et al. 1998.)
template <class T, class Visit>
PCISIM_XRAY_HD void traverse_cells(const T q0[3], const T dq[3], T ta, T tb, const int n[3], Visit& visit) {
  int cell[3], step[3];
  T t_next[3], t_delta[3];
  for (int a = 0; a < 3; ++a) {
    const T p = q0[a] + ta * dq[a];
    int c = static_cast<int>(std::floor(p));
    if (dq[a] < T(0) && T(c) == p) --c;  // leaving a boundary downward enters the lower cell
    c = c < 0 ? 0 : (c > n[a] - 1 ? n[a] - 1 : c);
    cell[a] = c;
    if (dq[a] > T(0)) {
      step[a] = 1;
      t_delta[a] = T(1) / dq[a];
      t_next[a] = (T(c + 1) - q0[a]) / dq[a];
    } else if (dq[a] < T(0)) {
      step[a] = -1;
      t_delta[a] = T(-1) / dq[a];
      t_next[a] = (T(c) - q0[a]) / dq[a];
    } else {
      step[a] = 0;
      t_delta[a] = T(0);
      t_next[a] = T(1e30);
    }
  }
  T t = ta;
  while (t < tb) {
    const int a = t_next[0] < t_next[1] ? (t_next[0] < t_next[2] ? 0 : 2) : (t_next[1] < t_next[2] ? 1 : 2);
    const T tn = t_next[a] < tb ? t_next[a] : tb;
    if (tn > t && !visit(cell[0], cell[1], cell[2], t, tn)) return;
    t = tn;
    cell[a] += step[a];
    t_next[a] += t_delta[a];
    if (cell[a] < 0 || cell[a] >= n[a]) return;
  }
}

// trilinear mu at padded coordinates (x, y, z) >= -1; zero outside (the border is zero, indices
// clamp). Truncation stands in for floor (a libm call without SSE4.1): for x in (-1, 0) it gives 0
// and a negative fraction, clamped to 0, which reads the zero border as floor would.
PCISIM_XRAY_HD float trilinear(const GridView& g, float x, float y, float z) {
  int ix = static_cast<int>(x), iy = static_cast<int>(y), iz = static_cast<int>(z);
  ix = ix < 0 ? 0 : (ix > g.nx - 2 ? g.nx - 2 : ix);
  iy = iy < 0 ? 0 : (iy > g.ny - 2 ? g.ny - 2 : iy);
  iz = iz < 0 ? 0 : (iz > g.nz - 2 ? g.nz - 2 : iz);
  float fx = x - ix, fy = y - iy, fz = z - iz;
  fx = fx < 0.f ? 0.f : (fx > 1.f ? 1.f : fx);
  fy = fy < 0.f ? 0.f : (fy > 1.f ? 1.f : fy);
  fz = fz < 0.f ? 0.f : (fz > 1.f ? 1.f : fz);
  const int64_t sy = g.nx, sz = int64_t(g.nx) * g.ny;
  const float* p = g.mu + ix + sy * iy + sz * iz;
  const float c00 = p[0] + fx * (p[1] - p[0]);
  const float c10 = p[sy] + fx * (p[sy + 1] - p[sy]);
  const float c01 = p[sz] + fx * (p[sz + 1] - p[sz]);
  const float c11 = p[sz + sy] + fx * (p[sz + sy + 1] - p[sz + sy]);
  const float c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
  return c0 + fz * (c1 - c0);
}

// sums trilinear mu at samples t_k = t0 + (k + 1/2) dt, k in [k_lo, k_hi); a branch-free loop
PCISIM_XRAY_HD float sum_samples(const GridView& g, const float x0[3], const float dx[3], float t0, float dt, int k_lo,
                                 int k_hi) {
  float acc = 0.f;
  for (int k = k_lo; k < k_hi; ++k) {
    const float t = t0 + (k + 0.5f) * dt;
    acc += trilinear(g, x0[0] + t * dx[0], x0[1] + t * dx[1], x0[2] + t * dx[2]);
  }
  return acc;
}

// one pixel's ray in padded voxel coordinates: x(t) = x0 + t dx, t in [0, 1] from the source to
// the pixel centre, clipped to [t0, t1] inside the grid; samples t_k = t0 + (k + 1/2) dt for
// k in [0, k_end), dt = step_voxels along the ray; len_mm turns a sum of samples times dt into mm
struct RaySetup {
  float x0[3], dx[3];
  float t0, t1, dt, len_mm;
  int k_end;
};

// the first sample index k with t_k >= t
PCISIM_XRAY_HD int first_sample_at_or_after(const RaySetup& s, float t) {
  return static_cast<int>(ceilf((t - s.t0) / s.dt - 0.5f));
}

// false (and k_end 0) when the ray misses the grid
PCISIM_XRAY_HD bool setup_ray(const GridView& g, const DetectorView& d, int c, int r, float step_voxels, RaySetup* s) {
  s->k_end = 0;
  const float oc = (c - 0.5f * (d.width - 1)) * d.pixel_mm, orow = (r - 0.5f * (d.height - 1)) * d.pixel_mm;
  float pix[3], x1[3];
  for (int a = 0; a < 3; ++a) pix[a] = d.center[a] + oc * d.u[a] + orow * d.v[a];
  s->len_mm = sqrtf((pix[0] - d.src[0]) * (pix[0] - d.src[0]) + (pix[1] - d.src[1]) * (pix[1] - d.src[1]) +
                    (pix[2] - d.src[2]) * (pix[2] - d.src[2]));
  for (int a = 0; a < 3; ++a) {
    s->x0[a] = g.m[4 * a] * d.src[0] + g.m[4 * a + 1] * d.src[1] + g.m[4 * a + 2] * d.src[2] + g.m[4 * a + 3];
    x1[a] = g.m[4 * a] * pix[0] + g.m[4 * a + 1] * pix[1] + g.m[4 * a + 2] * pix[2] + g.m[4 * a + 3];
    s->dx[a] = x1[a] - s->x0[a];
  }
  const float len_vox = sqrtf(s->dx[0] * s->dx[0] + s->dx[1] * s->dx[1] + s->dx[2] * s->dx[2]);
  if (!(len_vox > 0.f)) return false;
  // mu is non-zero only strictly inside padded [0, n-1]
  const float box[3] = {float(g.nx - 1), float(g.ny - 1), float(g.nz - 1)};
  s->t0 = 0.f;
  s->t1 = 1.f;
  if (!clip_to_box(s->x0, s->dx, box, &s->t0, &s->t1)) return false;
  s->dt = step_voxels / len_vox;
  s->k_end = first_sample_at_or_after(*s, s->t1);
  return true;
}

// calls run(k_lo, k_hi) for the runs of samples inside the bricks where on(i, j, k) holds, in
// order (walking the brick grid; runs of such bricks merged)
template <class On, class Run>
PCISIM_XRAY_HD void for_each_run_where(const GridView& g, const RaySetup& s, On& on, Run& run) {
  if (s.k_end <= 0) return;
  const float inv_b = 1.0f / g.brick;
  const float q0[3] = {s.x0[0] * inv_b, s.x0[1] * inv_b, s.x0[2] * inv_b};
  const float dq[3] = {s.dx[0] * inv_b, s.dx[1] * inv_b, s.dx[2] * inv_b};
  const int nb[3] = {g.bnx, g.bny, g.bnz};
  float run_start = -1.f, run_end = -1.f;
  // (a sample on a brick's face, as every plane sample of slice_ray where a brick begins, reads
  // that face alone, which both bricks' maxima include: on whichever side it rounds, it is
  // skipped only where it reads zeros)
  auto flush = [&]() {
    if (run_start >= 0.f) {
      const int lo = first_sample_at_or_after(s, run_start);
      const int hi = first_sample_at_or_after(s, run_end);
      run(lo > 0 ? lo : 0, hi < s.k_end ? hi : s.k_end);
      run_start = -1.f;
    }
  };
  auto visit = [&](int i, int j, int k, float ta, float tb) {
    if (on(i, j, k)) {
      if (run_start < 0.f) run_start = ta;
      run_end = tb;
    } else {
      flush();
    }
    return true;
  };
  traverse_cells(q0, dq, s.t0, s.t1, nb, visit);
  flush();
}

// calls run(k_lo, k_hi) for the sample ranges to sum, in order: [0, k_end) whole, or with
// skip_empty the runs of bricks holding some mu (walking the brick grid; the same samples' sum)
template <class Run>
PCISIM_XRAY_HD void for_each_run(const GridView& g, const RaySetup& s, bool skip_empty, Run& run) {
  if (s.k_end <= 0) return;
  if (!skip_empty) {
    run(0, s.k_end);
    return;
  }
  auto holds_mu = [&](int i, int j, int k) { return g.brick_max[i + g.bnx * (j + int64_t(g.bny) * k)] > 0.f; };
  for_each_run_where(g, s, holds_mu, run);
}

// the line integral (mu in 1/mm times mm) from the source to pixel (c, r) by trilinear ray
// marching every step_voxels (in voxel units along the ray); skip_empty walks the brick grid
// and samples only inside bricks holding some mu, which gives the same samples' sum
PCISIM_XRAY_HD float trilinear_ray(const GridView& g, const DetectorView& d, int c, int r, float step_voxels,
                                   bool skip_empty) {
  RaySetup s;
  if (!setup_ray(g, d, c, r, step_voxels, &s)) return 0.f;
  float acc = 0.f;
  auto run = [&](int lo, int hi) { acc += sum_samples(g, s.x0, s.dx, s.t0, s.dt, lo, hi); };
  for_each_run(g, s, skip_empty, run);
  return acc * s.dt * s.len_mm;
}

// Joseph's method (Joseph 1982, IEEE TMI 1(3)): a ray is sampled where it crosses the voxel
// planes x_a = j (j whole) of one axis a (its major one), mu read bilinearly in that plane, each
// sample weighted by the ray's length between planes. Where trilinear steps of one voxel read 8
// voxels a sample, this reads 4, and takes one sample per plane (a ray's length in voxels times
// |dx_a| / |dx| <= 1 of them).

// the axis along which dx is longest
PCISIM_XRAY_HD int major_axis(const float dx[3]) {
  const float ax = fabsf(dx[0]), ay = fabsf(dx[1]), az = fabsf(dx[2]);
  return ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
}

// a setup_ray RaySetup (any step) moved onto the planes of `axis`: dt = 1 / |dx_axis| and t0
// placed so that sample k lies on plane j0 + k sign(dx_axis) (*j0 set); the same RaySetup, so
// for_each_run skips empty bricks alike. False (k_end 0) when the ray runs along the planes or
// crosses none inside the grid
PCISIM_XRAY_HD bool to_planes(int axis, RaySetup* s, int* j0) {
  const float da = s->dx[axis];
  if (s->k_end <= 0 || fabsf(da) < 1e-6f) {
    s->k_end = 0;
    return false;
  }
  const float at = s->x0[axis] + s->t0 * da;  // where the ray enters the grid, along the axis
  *j0 = static_cast<int>(da > 0.f ? ceilf(at) : floorf(at));
  s->dt = 1.0f / fabsf(da);
  s->t0 = (static_cast<float>(*j0) - s->x0[axis]) / da - 0.5f * s->dt;
  s->k_end = first_sample_at_or_after(*s, s->t1);
  if (s->k_end < 0) s->k_end = 0;
  return s->k_end > 0;
}

// bilinear mu in plane ia of `axis` at (pb, pc), the other two axes in increasing order;
// indices and fractions clamped as trilinear() clamps them (the zero border outside)
PCISIM_XRAY_HD float bilinear_in_plane(const GridView& g, int axis, int ia, float pb, float pc) {
  const int n[3] = {g.nx, g.ny, g.nz};
  const int64_t stride[3] = {1, g.nx, int64_t(g.nx) * g.ny};
  const int b = axis == 0 ? 1 : 0, c = axis == 2 ? 1 : 2;
  ia = ia < 0 ? 0 : (ia > n[axis] - 1 ? n[axis] - 1 : ia);
  int ib = static_cast<int>(pb), ic = static_cast<int>(pc);
  ib = ib < 0 ? 0 : (ib > n[b] - 2 ? n[b] - 2 : ib);
  ic = ic < 0 ? 0 : (ic > n[c] - 2 ? n[c] - 2 : ic);
  float fb = pb - ib, fc = pc - ic;
  fb = fb < 0.f ? 0.f : (fb > 1.f ? 1.f : fb);
  fc = fc < 0.f ? 0.f : (fc > 1.f ? 1.f : fc);
  const float* p = g.mu + ia * stride[axis] + ib * stride[b] + ic * stride[c];
  const float c0 = p[0] + fb * (p[stride[b]] - p[0]);
  const float c1 = p[stride[c]] + fb * (p[stride[c] + stride[b]] - p[stride[c]]);
  return c0 + fc * (c1 - c0);
}

// the line integral to pixel (c, r) by Joseph's method along the ray's major axis; skip_empty as
// trilinear_ray's
PCISIM_XRAY_HD float slice_ray(const GridView& g, const DetectorView& d, int c, int r, bool skip_empty) {
  RaySetup s;
  if (!setup_ray(g, d, c, r, 1.0f, &s)) return 0.f;
  const int axis = major_axis(s.dx);
  int j0 = 0;
  if (!to_planes(axis, &s, &j0)) return 0.f;
  const int b = axis == 0 ? 1 : 0, cc = axis == 2 ? 1 : 2;
  const int sign = s.dx[axis] > 0.f ? 1 : -1;
  float acc = 0.f;
  auto run = [&](int lo, int hi) {
    for (int k = lo; k < hi; ++k) {
      const float t = s.t0 + (k + 0.5f) * s.dt;
      acc += bilinear_in_plane(g, axis, j0 + sign * k, s.x0[b] + t * s.dx[b], s.x0[cc] + t * s.dx[cc]);
    }
  };
  for_each_run(g, s, skip_empty, run);
  return acc * s.dt * s.len_mm;
}

}  // namespace pcisim::xray::ray
