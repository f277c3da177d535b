#include "physics/sdf/sdf_build_plan.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

namespace pcisim::physics::sdf {
namespace {

int find_root(std::vector<int>& parent, int v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

// sign of the yz edge function of edge (ia, ib) at (y, z), with the point symbolically nudged by
// (eps, eps^2) so it is never zero. The edge is evaluated with its lower vertex index first, so the
// two triangles sharing it compute bit-identical numbers and make opposite, consistent calls: a
// row through a vertex or an edge crosses the closed surface the right number of times.
int edge_side(const std::vector<Eigen::Vector3d>& v, int ia, int ib, double y, double z) {
  const bool flip = ia > ib;
  if (flip) std::swap(ia, ib);
  const Eigen::Vector3d& lo = v[ia];
  const Eigen::Vector3d& hi = v[ib];
  const double e = (hi.y() - lo.y()) * (z - lo.z()) - (hi.z() - lo.z()) * (y - lo.y());
  double s = e;
  if (s == 0.0) s = -(hi.z() - lo.z());
  if (s == 0.0) s = hi.y() - lo.y();
  const int side = s > 0 ? 1 : (s < 0 ? -1 : 0);
  return flip ? -side : side;
}

void build_parity_rows(const anatomy::TriangleMesh& mesh, const BuildGrid& g, ComponentPlan& c) {
  const int nj = c.j1 - c.j0 + 1, nk = c.k1 - c.k0 + 1;
  if (nj <= 0 || nk <= 0) {
    c.row_begin.assign(1, 0);
    return;
  }
  std::vector<std::pair<int64_t, double>> hits;
  const auto& v = mesh.vertices_m;
  for (uint32_t t : c.triangles) {
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3d &a = v[tri[0]], &b = v[tri[1]], &cc = v[tri[2]];
    const double ymin = std::min({a.y(), b.y(), cc.y()}), ymax = std::max({a.y(), b.y(), cc.y()});
    const double zmin = std::min({a.z(), b.z(), cc.z()}), zmax = std::max({a.z(), b.z(), cc.z()});
    const int jl = std::max(c.j0, static_cast<int>(std::ceil((ymin - g.origin[1]) / g.spacing)));
    const int jh = std::min(c.j1, static_cast<int>(std::floor((ymax - g.origin[1]) / g.spacing)));
    const int kl = std::max(c.k0, static_cast<int>(std::ceil((zmin - g.origin[2]) / g.spacing)));
    const int kh = std::min(c.k1, static_cast<int>(std::floor((zmax - g.origin[2]) / g.spacing)));
    for (int k = kl; k <= kh; ++k) {
      const double z = g.origin[2] + k * g.spacing;
      for (int j = jl; j <= jh; ++j) {
        const double y = g.origin[1] + j * g.spacing;
        const int s0 = edge_side(v, tri[1], tri[2], y, z);
        const int s1 = edge_side(v, tri[2], tri[0], y, z);
        const int s2 = edge_side(v, tri[0], tri[1], y, z);
        if (s0 == 0 || s0 != s1 || s1 != s2) continue;
        // where the row pierces the triangle, by barycentric weights of the yz projection
        auto ef = [y, z](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
          return (q.y() - p.y()) * (z - p.z()) - (q.z() - p.z()) * (y - p.y());
        };
        const double wa = ef(b, cc), wb = ef(cc, a), wc = ef(a, b);
        const double sum = wa + wb + wc;
        const double x =
            std::abs(sum) > 0 ? (wa * a.x() + wb * b.x() + wc * cc.x()) / sum : (a.x() + b.x() + cc.x()) / 3.0;
        hits.push_back({(j - c.j0) + int64_t(nj) * (k - c.k0), x});
      }
    }
  }
  std::sort(hits.begin(), hits.end());
  c.row_begin.assign(int64_t(nj) * nk + 1, 0);
  c.xs.resize(hits.size());
  for (size_t h = 0; h < hits.size(); ++h) {
    ++c.row_begin[hits[h].first + 1];
    c.xs[h] = hits[h].second;
  }
  std::partial_sum(c.row_begin.begin(), c.row_begin.end(), c.row_begin.begin());
}

}  // namespace

BuildPlan make_build_plan(const anatomy::TriangleMesh& mesh, double spacing_m, double padding_m, double band_m) {
  if (mesh.triangles.empty()) throw std::invalid_argument("SignedDistanceField: empty mesh");
  if (!(spacing_m > 0.0) || !std::isfinite(spacing_m)) {
    throw std::invalid_argument("SignedDistanceField: spacing_m must be > 0, got " + std::to_string(spacing_m));
  }
  if (!(padding_m >= 0.0) || !std::isfinite(padding_m)) {
    throw std::invalid_argument("SignedDistanceField: padding_m must be >= 0");
  }
  if (band_m <= 0.0) band_m = 4.0 * spacing_m;
  if (!std::isfinite(band_m)) throw std::invalid_argument("SignedDistanceField: band_m must be finite");

  BuildPlan plan;
  const int nv = static_cast<int>(mesh.vertices_m.size());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const auto& t : mesh.triangles) {
    for (int v : t) {
      if (v < 0 || v >= nv) throw std::invalid_argument("SignedDistanceField: triangle index out of range");
      if (!mesh.vertices_m[v].allFinite()) throw std::invalid_argument("SignedDistanceField: non-finite vertex");
      lo = lo.cwiseMin(mesh.vertices_m[v]);
      hi = hi.cwiseMax(mesh.vertices_m[v]);
    }
  }
  BuildGrid& g = plan.grid;
  g.spacing = spacing_m;
  g.band = static_cast<float>(band_m);
  double points = 1.0;
  for (int a = 0; a < 3; ++a) {
    g.origin[a] = lo[a] - padding_m;
    const double n = std::ceil((hi[a] - lo[a] + 2 * padding_m) / spacing_m) + 1;
    const double rounded = std::ceil(n / kBrick) * kBrick;  // whole bricks
    points *= rounded;
    if (rounded > 1 << 24 || points > static_cast<double>(kMaxGridPoints)) {
      throw std::invalid_argument("SignedDistanceField: grid too large for spacing " + std::to_string(spacing_m) +
                                  " (more than " + std::to_string(kMaxGridPoints) + " points)");
    }
    g.dims[a] = static_cast<int>(rounded);
    g.bricks[a] = g.dims[a] / kBrick;
  }
  const int64_t brick_count = int64_t(g.bricks[0]) * g.bricks[1] * g.bricks[2];
  plan.table.assign(brick_count, kBrickOutside);

  plan.triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    const auto& a = mesh.vertices_m[t[0]];
    const auto& b = mesh.vertices_m[t[1]];
    const auto& c = mesh.vertices_m[t[2]];
    plan.triangles.push_back({{a.x(), a.y(), a.z()}, {b.x(), b.y(), b.z()}, {c.x(), c.y(), c.z()}});
  }

  // connected components by shared vertices: each is one closed tube of the union
  std::vector<int> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& t : mesh.triangles) {
    const int r0 = find_root(parent, t[0]);
    parent[find_root(parent, t[1])] = r0;
    parent[find_root(parent, t[2])] = r0;
  }
  std::vector<int> component_of_root(nv, -1);
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const int root = find_root(parent, mesh.triangles[t][0]);
    if (component_of_root[root] < 0) {
      component_of_root[root] = static_cast<int>(plan.components.size());
      plan.components.emplace_back();
    }
    plan.components[component_of_root[root]].triangles.push_back(t);
  }

  // bricks within the band of each triangle (the same box the rasterizer visits)
  std::vector<int32_t> stamp(brick_count, -1);
  const double w = g.band;
  for (size_t ci = 0; ci < plan.components.size(); ++ci) {
    ComponentPlan& c = plan.components[ci];
    Eigen::Vector3d clo = Eigen::Vector3d::Constant(INFINITY), chi = -clo;
    for (uint32_t t : c.triangles) {
      int blo[3], bhi[3];
      bool empty = false;
      for (int a = 0; a < 3; ++a) {
        const double v0 = mesh.vertices_m[mesh.triangles[t][0]][a];
        const double v1 = mesh.vertices_m[mesh.triangles[t][1]][a];
        const double v2 = mesh.vertices_m[mesh.triangles[t][2]][a];
        const double mn = std::min({v0, v1, v2}), mx = std::max({v0, v1, v2});
        clo[a] = std::min(clo[a], mn);
        chi[a] = std::max(chi[a], mx);
        const int l = std::max(0, static_cast<int>(std::ceil((mn - w - g.origin[a]) / g.spacing)));
        const int h = std::min(g.dims[a] - 1, static_cast<int>(std::floor((mx + w - g.origin[a]) / g.spacing)));
        if (l > h) empty = true;
        blo[a] = l / kBrick;
        bhi[a] = h / kBrick;
      }
      if (empty) continue;
      for (int bz = blo[2]; bz <= bhi[2]; ++bz)
        for (int by = blo[1]; by <= bhi[1]; ++by)
          for (int bx = blo[0]; bx <= bhi[0]; ++bx) {
            const int64_t b = bx + int64_t(g.bricks[0]) * (by + int64_t(g.bricks[1]) * bz);
            if (plan.table[b] < 0) {
              // wide walls at a fine spacing: refused before the pool and the keys are allocated
              if (int64_t(plan.pool_bricks() + 1) * kBrickPoints > kMaxBandPoints)
                throw std::invalid_argument("SignedDistanceField: the walls' band needs more than " +
                                            std::to_string(kMaxBandPoints) + " grid points at spacing " +
                                            std::to_string(spacing_m) + " (a lumen too large for it)");
              plan.table[b] = plan.pool_bricks();
              plan.pool_brick_coords.insert(plan.pool_brick_coords.end(), {bx, by, bz});
            }
            if (stamp[b] != static_cast<int32_t>(ci)) {
              stamp[b] = static_cast<int32_t>(ci);
              c.bricks.push_back(plan.table[b]);
            }
          }
    }
    for (int a = 0; a < 3; ++a) {
      c.lo[a] = std::clamp(static_cast<int>(std::floor((clo[a] - g.origin[a]) / g.spacing)), 0, g.dims[a] - 1);
      c.hi[a] = std::clamp(static_cast<int>(std::ceil((chi[a] - g.origin[a]) / g.spacing)), 0, g.dims[a] - 1);
    }
    c.j0 = c.lo[1], c.j1 = c.hi[1], c.k0 = c.lo[2], c.k1 = c.hi[2];
  }
  g.table = plan.table.data();
  for (ComponentPlan& c : plan.components) build_parity_rows(mesh, g, c);
  return plan;
}

void fold_components_cpu(const BuildPlan& plan, std::vector<float>& pool) {
  const BuildGrid& g = plan.grid;
  std::vector<uint64_t> keys(pool.size(), kNoKey);
  for (const ComponentPlan& c : plan.components) {
    for (int32_t b : c.bricks) std::fill_n(keys.begin() + int64_t(b) * kBrickPoints, kBrickPoints, kNoKey);
    for (uint32_t t : c.triangles) {
      rasterize_triangle(g, plan.triangles[t], t, keys.data(), [](uint64_t* slot, uint64_t key) {
        if (key < *slot) *slot = key;
      });
    }
    const ParityView pv = c.parity();
    for (int32_t b : c.bricks) {
      const int* bc = &plan.pool_brick_coords[3 * int64_t(b)];
      for (int l = 0; l < kBrickPoints; ++l) {
        const int i = bc[0] * kBrick + l % kBrick;
        const int j = bc[1] * kBrick + (l / kBrick) % kBrick;
        const int k = bc[2] * kBrick + l / (kBrick * kBrick);
        const int64_t idx = int64_t(b) * kBrickPoints + l;
        const float v = component_value(g, plan.triangles.data(), pv, keys[idx], i, j, k);
        pool[idx] = std::min(pool[idx], v);
      }
    }
  }
}

void classify_remaining(BuildPlan& plan, std::vector<float>& pool) {
  const BuildGrid& g = plan.grid;
  const int32_t pool_bricks = plan.pool_bricks();
  std::vector<char> own(pool_bricks, 0);
  for (const ComponentPlan& c : plan.components) {
    const ParityView pv = c.parity();
    for (int32_t b : c.bricks) own[b] = 1;
    int blo[3], bhi[3];
    for (int a = 0; a < 3; ++a) blo[a] = c.lo[a] / kBrick, bhi[a] = c.hi[a] / kBrick;
    for (int bz = blo[2]; bz <= bhi[2]; ++bz)
      for (int by = blo[1]; by <= bhi[1]; ++by)
        for (int bx = blo[0]; bx <= bhi[0]; ++bx) {
          const int64_t bi = bx + int64_t(g.bricks[0]) * (by + int64_t(g.bricks[1]) * bz);
          int32_t& entry = plan.table[bi];
          if (entry == kBrickInside) continue;
          if (entry == kBrickOutside) {
            // no surface comes near this brick: it is all inside or all outside this tube
            const int i = bx * kBrick, j = by * kBrick, k = bz * kBrick;
            if (inside_by_parity(pv, g.origin[0] + i * g.spacing, j, k)) entry = kBrickInside;
            continue;
          }
          if (own[entry]) continue;  // folded already, with this tube's own values
          // another tube's band bricks: a point inside this tube is inside the lumen, whatever
          // the other tube says (its wall there is no wall of the union)
          float* values = &pool[int64_t(entry) * kBrickPoints];
          for (int l = 0; l < kBrickPoints; ++l) {
            const int i = bx * kBrick + l % kBrick;
            const int j = by * kBrick + (l / kBrick) % kBrick;
            const int k = bz * kBrick + l / (kBrick * kBrick);
            if (values[l] > -g.band && inside_by_parity(pv, g.origin[0] + i * g.spacing, j, k)) {
              values[l] = -g.band;
            }
          }
        }
    for (int32_t b : c.bricks) own[b] = 0;
  }
}

}  // namespace pcisim::physics::sdf
