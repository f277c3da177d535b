#include "modeling/cta/centerline_tracing.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>
#include <unordered_map>

namespace pcisim::modeling {

std::vector<TracedBranch> trace_centerlines(const Clipping& clip, const CoronaryPiece& piece, const TracingOptions& o) {
  const ImageGrid& g = clip.distance_mm.grid;
  const int32_t n = static_cast<int32_t>(piece.voxels.size());
  std::unordered_map<int64_t, int32_t> id;
  id.reserve(n * 2);
  for (int32_t a = 0; a < n; ++a) id.emplace(piece.voxels[a], a);
  std::vector<double> d(n);
  double d_max = 1e-6;
  for (int32_t a = 0; a < n; ++a) {
    d[a] = clip.distance_mm.v[piece.voxels[a]];
    d_max = std::max(d_max, d[a]);
  }
  // neighbour lists once (ids), so both searches below are plain graph walks
  const Neighbours26 nb(g.spacing_mm);
  std::vector<int32_t> adj(size_t(n) * 26, -1);
  for (int32_t a = 0; a < n; ++a) {
    const auto [i, j, k] = g.ijk(piece.voxels[a]);
    for (int q = 0; q < 26; ++q) {
      const int64_t x = i + nb.d[q][0], y = j + nb.d[q][1], z = k + nb.d[q][2];
      if (!g.inside(x, y, z)) continue;
      const auto it = id.find(g.index(x, y, z));
      if (it != id.end()) adj[size_t(a) * 26 + q] = it->second;
    }
  }

  // minimal paths from the ostium under the centring cost
  const int32_t root = id.at(piece.ostium);
  std::vector<double> cost(n, 1e300), length(n, 0.0);
  std::vector<int32_t> parent(n, -1);
  using Item = std::pair<double, int32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> heap;
  cost[root] = 0;
  heap.push({0.0, root});
  while (!heap.empty()) {
    const auto [c, a] = heap.top();
    heap.pop();
    if (c > cost[a]) continue;
    for (int q = 0; q < 26; ++q) {
      const int32_t b = adj[size_t(a) * 26 + q];
      if (b < 0) continue;
      const double w = 1.0 + o.penalty_scale * std::pow(1.0 - std::min(d[b], d_max) / d_max, o.penalty_power);
      const double cb = c + nb.length_mm[q] * w;
      if (cb < cost[b]) {
        cost[b] = cb;
        parent[b] = a;
        length[b] = length[a] + nb.length_mm[q];
        heap.push({cb, b});
      }
    }
  }

  // far ends in order of path length; each new path runs back until it meets the tree
  std::vector<int32_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return length[a] > length[b]; });
  std::vector<uint8_t> covered(n, 0);
  std::vector<int32_t> branch_of(n, -1), point_of(n, -1);
  std::vector<TracedBranch> out;
  const Eigen::Vector3d inv_sp = g.spacing_mm.cwiseInverse();
  auto cover = [&](int32_t a) {
    // voxels within the covering radius of a, by a walk over the neighbour graph
    const double r = o.cover_scale * d[a] + o.cover_min_mm;
    const auto [i0, j0, k0] = g.ijk(piece.voxels[a]);
    const int64_t ri = int64_t(r * inv_sp.x()) + 1, rj = int64_t(r * inv_sp.y()) + 1, rk = int64_t(r * inv_sp.z()) + 1;
    for (int64_t k = k0 - rk; k <= k0 + rk; ++k) {
      for (int64_t j = j0 - rj; j <= j0 + rj; ++j) {
        for (int64_t i = i0 - ri; i <= i0 + ri; ++i) {
          if (!g.inside(i, j, k)) continue;
          const Eigen::Vector3d dv((i - i0) * g.spacing_mm.x(), (j - j0) * g.spacing_mm.y(),
                                   (k - k0) * g.spacing_mm.z());
          if (dv.squaredNorm() > r * r) continue;
          const auto it = id.find(g.index(i, j, k));
          if (it != id.end()) covered[it->second] = 1;
        }
      }
    }
  };
  for (int32_t tip : order) {
    if (covered[tip] || cost[tip] >= 1e300) continue;
    std::vector<int32_t> path;
    int32_t a = tip;
    while (a >= 0 && branch_of[a] < 0) {
      path.push_back(a);
      a = parent[a];
    }
    const int32_t join = a;  // -1 when the path reached the ostium without meeting the tree
    if (join >= 0) path.push_back(join);
    std::reverse(path.begin(), path.end());
    const double len = length[tip] - (join >= 0 ? length[join] : 0.0);
    // the part beyond what the tree already covers: a bump on a wall or a staircase corner the
    // cover just missed sticks out by little, however far its path runs inside the vessel
    double beyond = len;
    for (int32_t v : path) {
      if (!covered[v]) {
        beyond = length[tip] - length[v];
        break;
      }
    }
    const bool first = out.empty();
    const bool kept = first || (join >= 0 && beyond >= o.min_branch_mm && len >= o.min_branch_radii * d[join]);
    for (int32_t v : path) cover(v);
    covered[tip] = 1;
    if (!kept) continue;
    TracedBranch b;
    if (join >= 0) {
      b.parent = branch_of[join];
      b.parent_point = point_of[join];
    }
    const int bi = static_cast<int>(out.size());
    for (size_t m = 0; m < path.size(); ++m) {
      const int32_t v = path[m];
      const auto [i, j, k] = g.ijk(piece.voxels[v]);
      b.points_mm.push_back(g.physical_mm(Eigen::Vector3d(double(i), double(j), double(k))));
      b.radius_mm.push_back(d[v]);
      if (branch_of[v] < 0) {
        branch_of[v] = bi;
        point_of[v] = static_cast<int>(m);
      }
    }
    out.push_back(std::move(b));
  }
  return out;
}

}  // namespace pcisim::modeling
