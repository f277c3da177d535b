#pragma once
// The per-point and per-triangle steps of building and sampling the SDF, written once for both
// the CPU loops (signed_distance_field.cc) and the CUDA kernels (signed_distance_field_cuda.cu),
// so the two twins run the same arithmetic. Plain structs and raw pointers only: no Eigen here.
#include <cmath>
#include <cstdint>

#ifdef __CUDACC__
#define PCISIM_HD __host__ __device__
#else
#define PCISIM_HD
#endif

namespace pcisim::physics::sdf {

constexpr int kBrick = 8;  // bricks of 8x8x8 grid points
constexpr int kBrickPoints = kBrick * kBrick * kBrick;
constexpr int32_t kBrickOutside = -1;      // brick table: no surface near, outside the lumen
constexpr int32_t kBrickInside = -2;       // no surface near, inside the lumen
constexpr uint64_t kNoKey = ~uint64_t{0};  // no triangle has reached this point yet
constexpr double kFarDistanceM = 1.0;      // reported for non-finite query points

struct V3 {
  double x, y, z;
};
PCISIM_HD inline V3 sub(V3 a, V3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
PCISIM_HD inline V3 add(V3 a, V3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
PCISIM_HD inline V3 mul(V3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
PCISIM_HD inline double dot(V3 a, V3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
PCISIM_HD inline V3 cross(V3 a, V3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// the grid and its bricks, as the sampler and the kernels see them
struct GridView {
  double origin[3];
  double spacing;
  int dims[3];           // grid points per axis (a multiple of kBrick)
  int bricks[3];         // dims / kBrick
  float band;            // |values| never exceed this
  const int32_t* table;  // bricks[0]*bricks[1]*bricks[2] entries: pool brick, or kBrickOutside/Inside
  const float* pool;     // kBrickPoints floats per pool brick, x fastest within a brick
};

PCISIM_HD inline int64_t brick_index(const GridView& g, int i, int j, int k) {
  return (i / kBrick) + int64_t(g.bricks[0]) * ((j / kBrick) + int64_t(g.bricks[1]) * (k / kBrick));
}
PCISIM_HD inline int local_index(int i, int j, int k) {
  return (i % kBrick) + kBrick * ((j % kBrick) + kBrick * (k % kBrick));
}

// value at a grid point (indices assumed inside the grid)
PCISIM_HD inline float grid_value(const GridView& g, int i, int j, int k) {
  const int32_t b = g.table[brick_index(g, i, j, k)];
  if (b >= 0) return g.pool[int64_t(b) * kBrickPoints + local_index(i, j, k)];
  return b == kBrickInside ? -g.band : g.band;
}

// trilinear sample with the analytic gradient of the interpolant (paper, text after eq 14).
// Outside the grid: the point is clamped onto the grid box, sampled there, and the distance from
// the box to the point is added; the gradient then points from the box toward the point, so a
// body that left the grid is pushed back toward it. Non-finite points: kFarDistanceM, gradient +x.
// The gradient is unit length; where the interpolant is flat (deep inside the clamped band) it is
// +x. Nothing here can produce NaN from finite grid values.
PCISIM_HD inline void sample_grid(const GridView& g, const double p[3], double* distance, double gradient[3],
                                  bool* inside_grid) {
  gradient[0] = 1.0, gradient[1] = 0.0, gradient[2] = 0.0;
  if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
    *distance = kFarDistanceM;
    *inside_grid = false;
    return;
  }
  double u[3], f[3], out[3];
  int i0[3];
  bool inside = true;
  double outside_sq = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double hi = double(g.dims[a] - 1);
    const double x = (p[a] - g.origin[a]) / g.spacing;
    u[a] = x < 0.0 ? 0.0 : (x > hi ? hi : x);
    out[a] = (x - u[a]) * g.spacing;  // 0 inside the box along this axis
    if (out[a] != 0.0) inside = false;
    outside_sq += out[a] * out[a];
    int c = int(u[a]);
    if (c > g.dims[a] - 2) c = g.dims[a] - 2;
    i0[a] = c;
    f[a] = u[a] - c;
  }
  double v[2][2][2];
  for (int dk = 0; dk < 2; ++dk)
    for (int dj = 0; dj < 2; ++dj)
      for (int di = 0; di < 2; ++di) v[dk][dj][di] = grid_value(g, i0[0] + di, i0[1] + dj, i0[2] + dk);
  const double fx = f[0], fy = f[1], fz = f[2];
  // interpolate along x, then y, then z; derivatives of the same polynomial
  const double c00 = v[0][0][0] + fx * (v[0][0][1] - v[0][0][0]);
  const double c10 = v[0][1][0] + fx * (v[0][1][1] - v[0][1][0]);
  const double c01 = v[1][0][0] + fx * (v[1][0][1] - v[1][0][0]);
  const double c11 = v[1][1][0] + fx * (v[1][1][1] - v[1][1][0]);
  const double c0 = c00 + fy * (c10 - c00);
  const double c1 = c01 + fy * (c11 - c01);
  double d = c0 + fz * (c1 - c0);
  const double dx0 = (v[0][0][1] - v[0][0][0]) + fy * ((v[0][1][1] - v[0][1][0]) - (v[0][0][1] - v[0][0][0]));
  const double dx1 = (v[1][0][1] - v[1][0][0]) + fy * ((v[1][1][1] - v[1][1][0]) - (v[1][0][1] - v[1][0][0]));
  double gx = dx0 + fz * (dx1 - dx0);
  double gy = (c10 - c00) + fz * ((c11 - c01) - (c10 - c00));
  double gz = c1 - c0;
  if (!inside) {
    const double out_len = std::sqrt(outside_sq);
    d += out_len;
    gx = out[0], gy = out[1], gz = out[2];
  }
  const double len = std::sqrt(gx * gx + gy * gy + gz * gz);
  if (len > 1e-300 && std::isfinite(len)) {
    gradient[0] = gx / len, gradient[1] = gy / len, gradient[2] = gz / len;
  }
  *distance = d;
  *inside_grid = inside;
}

// closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5, by Voronoi
// regions). region: 0 the face's interior, 1 an edge, 2 a vertex.
PCISIM_HD inline V3 closest_on_triangle(V3 p, V3 a, V3 b, V3 c, int* region) {
  const V3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    *region = 2;
    return a;
  }
  const V3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) {
    *region = 2;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    *region = 1;
    return add(a, mul(ab, d1 / (d1 - d3)));
  }
  const V3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) {
    *region = 2;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    *region = 1;
    return add(a, mul(ac, d2 / (d2 - d6)));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    *region = 1;
    return add(b, mul(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
  }
  *region = 0;
  const double denom = 1.0 / (va + vb + vc);
  return add(a, add(mul(ab, vb * denom), mul(ac, vc * denom)));
}

PCISIM_HD inline uint64_t make_key(float distance, uint32_t triangle) {
  // non-negative floats order like their bit patterns, so the smallest key is the nearest
  // triangle (ties: the lowest triangle index, on the CPU and the GPU alike)
  union {
    float f;
    uint32_t u;
  } bits;
  bits.f = distance;
  return (uint64_t(bits.u) << 32) | triangle;
}
PCISIM_HD inline float key_distance(uint64_t key) {
  union {
    float f;
    uint32_t u;
  } bits;
  bits.u = uint32_t(key >> 32);
  return bits.f;
}

struct Triangle {
  V3 a, b, c;
};

// grid geometry shared by the build steps
struct BuildGrid {
  double origin[3];
  double spacing;
  int dims[3];
  int bricks[3];
  float band;
  const int32_t* table;
};

PCISIM_HD inline V3 grid_point(const BuildGrid& g, int i, int j, int k) {
  return {g.origin[0] + i * g.spacing, g.origin[1] + j * g.spacing, g.origin[2] + k * g.spacing};
}

// the paper's prism step (fig. 8a): the triangle swept +-band along its face normal, its AABB,
// and every grid point of that AABB that lies inside the prism's slab gets the exact distance to
// the triangle if it beats what it holds. Update(key_slot, key) is a plain or atomic min.
template <class Update>
PCISIM_HD inline void rasterize_triangle(const BuildGrid& g, const Triangle& t, uint32_t index, uint64_t* keys,
                                         Update update) {
  const V3 n_raw = cross(sub(t.b, t.a), sub(t.c, t.a));
  const double n_len = std::sqrt(dot(n_raw, n_raw));
  if (!(n_len > 0.0)) return;  // a degenerate triangle has no face; its neighbours cover it
  const V3 n = mul(n_raw, 1.0 / n_len);
  const double w = g.band;
  int lo[3], hi[3];
  const double tv[3][3] = {{t.a.x, t.b.x, t.c.x}, {t.a.y, t.b.y, t.c.y}, {t.a.z, t.b.z, t.c.z}};
  for (int a = 0; a < 3; ++a) {
    // the prism's AABB would grow the triangle's box by |n_a| * band; growing it by the band on
    // every axis also covers the wedges outside convex edges that no prism contains
    double mn = tv[a][0], mx = tv[a][0];
    for (int v = 1; v < 3; ++v) mn = tv[a][v] < mn ? tv[a][v] : mn, mx = tv[a][v] > mx ? tv[a][v] : mx;
    const double grow = w;
    const double l = std::ceil((mn - grow - g.origin[a]) / g.spacing);
    const double h = std::floor((mx + grow - g.origin[a]) / g.spacing);
    lo[a] = l < 0 ? 0 : int(l);
    hi[a] = h > g.dims[a] - 1 ? g.dims[a] - 1 : int(h);
    if (lo[a] > hi[a]) return;
  }
  const double step = n.x * g.spacing;  // change of the plane distance per step in i
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j) {
      // along the row only the run inside the prism's slab |plane| <= band can be near the face
      const double plane0 = dot(sub(grid_point(g, 0, j, k), t.a), n);
      int i_lo = lo[0], i_hi = hi[0];
      if (step != 0.0) {
        double x0 = (-w - plane0) / step, x1 = (w - plane0) / step;
        if (x0 > x1) {
          const double tmp = x0;
          x0 = x1;
          x1 = tmp;
        }
        const double c0 = std::ceil(x0), c1 = std::floor(x1);
        if (c0 > i_lo) i_lo = c0 > i_hi ? i_hi + 1 : int(c0);
        if (c1 < i_hi) i_hi = c1 < i_lo ? i_lo - 1 : int(c1);
      } else if (std::fabs(plane0) > w) {
        continue;
      }
      for (int i = i_lo; i <= i_hi; ++i) {
        const V3 p = grid_point(g, i, j, k);
        const double plane = dot(sub(p, t.a), n);
        if (std::fabs(plane) > w) continue;  // rounding at the run's ends
        const int32_t b =
            g.table[(i / kBrick) + int64_t(g.bricks[0]) * ((j / kBrick) + int64_t(g.bricks[1]) * (k / kBrick))];
        if (b < 0) continue;  // cannot happen for a planned grid; keeps a bad plan from writing wild
        uint64_t* slot = keys + int64_t(b) * kBrickPoints + local_index(i, j, k);
        // the plane distance bounds the exact one from below: skip what cannot win. (kNoKey reads
        // as NaN, which never prunes; a stale read on the GPU only prunes less.)
        if (std::fabs(plane) > double(key_distance(*slot))) continue;
        int region;
        const V3 q = closest_on_triangle(p, t.a, t.b, t.c, &region);
        const V3 pq = sub(p, q);
        const float d = float(std::sqrt(dot(pq, pq)));
        if (d > w) continue;
        update(slot, make_key(d, index));
      }
    }
}

// a component's inside test by ray parity along +x: the x of every crossing of the grid row
// (j, k) with the component's surface, sorted per row (compressed rows over [j0,j1]x[k0,k1])
struct ParityView {
  int j0, j1, k0, k1;
  const int32_t* row_begin;  // (j1-j0+1)*(k1-k0+1)+1 offsets into xs
  const double* xs;
};

PCISIM_HD inline bool inside_by_parity(const ParityView& pv, double x, int j, int k) {
  if (j < pv.j0 || j > pv.j1 || k < pv.k0 || k > pv.k1) return false;
  const int64_t r = (j - pv.j0) + int64_t(pv.j1 - pv.j0 + 1) * (k - pv.k0);
  int lo = pv.row_begin[r], hi = pv.row_begin[r + 1];
  const int first = lo;
  while (lo < hi) {  // first crossing at or beyond x
    const int mid = (lo + hi) / 2;
    if (pv.xs[mid] < x)
      lo = mid + 1;
    else
      hi = mid;
  }
  return ((lo - first) & 1) != 0;
}

// one grid point of a component's bricks: turn the nearest-triangle key into the component's
// signed distance and fold it into the union (min over components). Sign: eq 14 (the face normal
// of the nearest triangle) where the nearest point is inside that face; where it is an edge or a
// vertex eq 14 is ambiguous and the parity test decides; beyond the band, parity gives +-band.
PCISIM_HD inline float component_value(const BuildGrid& g, const Triangle* triangles, const ParityView& pv,
                                       uint64_t key, int i, int j, int k) {
  const V3 p = grid_point(g, i, j, k);
  if (key == kNoKey || key_distance(key) > g.band) {
    return inside_by_parity(pv, p.x, j, k) ? -g.band : g.band;
  }
  const float d = key_distance(key);
  const Triangle& t = triangles[uint32_t(key & 0xffffffffu)];
  int region;
  const V3 q = closest_on_triangle(p, t.a, t.b, t.c, &region);
  bool inside;
  if (region == 0) {
    const V3 n = cross(sub(t.b, t.a), sub(t.c, t.a));
    inside = dot(sub(p, q), n) < 0.0;  // eq 14: outward normal, negative behind the face
  } else {
    inside = inside_by_parity(pv, p.x, j, k);
  }
  return inside ? -d : d;
}

}  // namespace pcisim::physics::sdf
