#include "anatomy/vessel/lumen_surface.h"

#include "anatomy/mesh/kuhn_tetrahedra.h"
#include "anatomy/vessel/lumen_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

namespace pcisim::anatomy {
namespace {

using Eigen::Vector3d;

constexpr int kBrick = 8;  // nodes per brick edge (cells whose lower corner is in the brick)
constexpr int kBrickNodes = kBrick * kBrick * kBrick;
constexpr double kDilationCells = 3.0;  // a segment's box grows by this many cells before bricks are marked

// one swept sphere, with what its distance needs precomputed
struct Segment {
  Vector3d a, b;
  double ra = 0, rb = 0;
  Vector3d axis = Vector3d::UnitX();  // unit, a -> b
  double length = 0;
  double sin_t = 0, cos_t = 1;  // the cone's half-angle: sin = (ra - rb) / length
  bool one_sphere = true;       // one sphere holds the other (or a == b): the nearer sphere decides
  Vector3d lo, hi;              // bounding box
};

Segment make_segment(const Vector3d& a, double ra, const Vector3d& b, double rb) {
  Segment s;
  s.a = a;
  s.b = b;
  s.ra = ra;
  s.rb = rb;
  s.length = (b - a).norm();
  s.one_sphere = s.length <= std::abs(ra - rb) || s.length < 1e-12;
  if (!s.one_sphere) {
    s.axis = (b - a) / s.length;
    s.sin_t = (ra - rb) / s.length;
    s.cos_t = std::sqrt(1.0 - s.sin_t * s.sin_t);
  }
  s.lo = (a.array() - ra).min(b.array() - rb);
  s.hi = (a.array() + ra).max(b.array() + rb);
  return s;
}

// signed distance to the convex hull of the spheres (a, ra) and (b, rb), in the half-plane
// (t along the axis, s from it). The hull's profile is circle a, the common tangent line, circle
// b; which one is nearest follows from the position lambda along the tangent line
double segment_distance(const Segment& g, const Vector3d& p) {
  if (g.one_sphere) return std::min((p - g.a).norm() - g.ra, (p - g.b).norm() - g.rb);
  const Vector3d ap = p - g.a;
  const double t = ap.dot(g.axis);
  const double s = std::sqrt(std::max(0.0, ap.squaredNorm() - t * t));
  const double lambda = t * g.cos_t - s * g.sin_t;
  if (lambda <= 0.0) return std::sqrt(t * t + s * s) - g.ra;
  if (lambda >= g.length * g.cos_t) return std::sqrt((t - g.length) * (t - g.length) + s * s) - g.rb;
  return t * g.sin_t + s * g.cos_t - g.ra;
}

bool excluded(const StitchedLumenSpec& spec, const std::string& name) {
  return std::find(spec.exclude.begin(), spec.exclude.end(), name) != spec.exclude.end();
}

// the segments of one branch: its centerline, extended back toward its parent's point as
// loft_lumen does (unless the parent is excluded: the extension would reach into its lumen and
// join trees that are apart), repeated points dropped
void branch_segments(const VesselTree& tree, const VesselBranch& branch, const StitchedLumenSpec& spec,
                     std::vector<Segment>& out) {
  std::vector<Vector3d> pts;
  std::vector<double> radii;
  const bool parent_kept = branch.parent >= 0 && branch.parent < static_cast<int>(tree.branches.size()) &&
                           !excluded(spec, tree.branches[branch.parent].name);
  branch_sweep_points(tree, branch, parent_kept, &pts, &radii);
  if (pts.size() == 1) out.push_back(make_segment(pts[0], radii[0], pts[0], radii[0]));
  for (size_t i = 0; i + 1 < pts.size(); ++i) out.push_back(make_segment(pts[i], radii[i], pts[i + 1], radii[i + 1]));
}

// 20 bits per axis
constexpr int64_t kAxisLimit = int64_t{1} << 20;
uint64_t pack(int64_t i, int64_t j, int64_t k) {
  return uint64_t(i) | (uint64_t(j) << 20) | (uint64_t(k) << 40);
}

// the cube's six tetrahedra (anatomy/mesh/kuhn_tetrahedra.h) and the even permutations of four
struct TetTable {
  std::array<std::array<int, 4>, 6> tets{};
  std::array<std::array<int, 4>, 12> even_perms{};
  TetTable() {
    for (int t = 0; t < 6; ++t)
      for (int c = 0; c < 4; ++c) tets[t][c] = kKuhnTetrahedra[t][c];
    std::array<int, 4> p = {0, 1, 2, 3};
    int n = 0;
    do {
      int inversions = 0;
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) inversions += p[i] > p[j];
      if (inversions % 2 == 0) even_perms[n++] = p;
    } while (std::next_permutation(p.begin(), p.end()));
  }
};

const TetTable& tet_table() {
  static const TetTable table;
  return table;
}

// component label of each vertex (union-find over triangle edges)
std::vector<int> vertex_components(const TriangleMesh& mesh) {
  std::vector<int> parent(mesh.vertices_m.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& t : mesh.triangles)
    for (int e = 0; e < 3; ++e) parent[root(t[e])] = root(t[(e + 1) % 3]);
  for (size_t v = 0; v < parent.size(); ++v) parent[v] = root(int(v));
  return parent;
}

size_t drop_inner_shells(TriangleMesh& mesh) {
  const std::vector<int> label = vertex_components(mesh);
  std::unordered_map<int, double> volume;
  for (const auto& t : mesh.triangles)
    volume[label[t[0]]] += mesh.vertices_m[t[0]].dot(mesh.vertices_m[t[1]].cross(mesh.vertices_m[t[2]]));
  size_t dropped = 0;
  for (const auto& [c, v] : volume) dropped += v <= 0.0;
  if (dropped == 0) return 0;
  std::vector<int> index(mesh.vertices_m.size(), -1);
  TriangleMesh kept;
  for (const auto& t : mesh.triangles) {
    if (volume[label[t[0]]] <= 0.0) continue;
    std::array<int, 3> tri;
    for (int e = 0; e < 3; ++e) {
      if (index[t[e]] < 0) {
        index[t[e]] = static_cast<int>(kept.vertices_m.size());
        kept.vertices_m.push_back(mesh.vertices_m[t[e]]);
      }
      tri[e] = index[t[e]];
    }
    kept.triangles.push_back(tri);
  }
  mesh = std::move(kept);
  return dropped;
}

}  // namespace

double swept_sphere_distance_m(const Vector3d& p_m, const Vector3d& a_m, double ra_m, const Vector3d& b_m,
                               double rb_m) {
  return segment_distance(make_segment(a_m, ra_m, b_m, rb_m), p_m);
}

TriangleMesh stitch_lumen(const VesselTree& tree, const StitchedLumenSpec& spec, StitchedLumenStats* stats) {
  TriangleMesh mesh;
  std::vector<Segment> segs;
  for (const auto& b : tree.branches) {
    if (!excluded(spec, b.name)) branch_segments(tree, b, spec, segs);
  }
  // a radius of zero or less has no lumen
  std::erase_if(segs, [](const Segment& s) { return !(s.ra > 0.0) || !(s.rb > 0.0); });
  if (segs.empty()) return mesh;

  double h = spec.spacing_m;
  if (spec.cells_per_min_radius > 0.0) {
    double r_min = std::numeric_limits<double>::infinity();
    for (const auto& s : segs) r_min = std::min({r_min, s.ra, s.rb});
    h = std::min(h, r_min / spec.cells_per_min_radius);
  }
  if (!(h > 0.0) || !std::isfinite(h)) throw std::invalid_argument("stitch_lumen: the grid spacing must be > 0");

  Vector3d lo = segs[0].lo, hi = segs[0].hi;
  for (const auto& s : segs) {
    lo = lo.cwiseMin(s.lo);
    hi = hi.cwiseMax(s.hi);
  }
  const double pad = (kDilationCells + 1.0) * h;
  const Vector3d origin = lo.array() - pad;
  const Eigen::Vector3d extent = (hi - lo).array() + 2.0 * pad;
  if ((extent / h).maxCoeff() >= double(kAxisLimit - 2 * kBrick))
    throw std::invalid_argument("stitch_lumen: the tree spans more than 2^20 grid cells on an axis");
  auto node_position = [&](int64_t i, int64_t j, int64_t k) { return Vector3d(origin + h * Vector3d(i, j, k)); };

  // bricks touched by each segment's dilated box, with the segments that touch them
  std::unordered_map<uint64_t, std::vector<int>> brick_segments;
  for (size_t si = 0; si < segs.size(); ++si) {
    const Vector3d a = ((segs[si].lo - origin).array() / h - kDilationCells).floor();
    const Vector3d b = ((segs[si].hi - origin).array() / h + kDilationCells).ceil();
    const Eigen::Vector3i b0 = (a.array().max(0.0) / kBrick).floor().cast<int>();
    const Eigen::Vector3i b1 = (b.array().max(0.0) / kBrick).floor().cast<int>();
    for (int z = b0.z(); z <= b1.z(); ++z)
      for (int y = b0.y(); y <= b1.y(); ++y)
        for (int x = b0.x(); x <= b1.x(); ++x) brick_segments[pack(x, y, z)].push_back(static_cast<int>(si));
  }
  std::vector<uint64_t> keys;
  keys.reserve(brick_segments.size());
  for (const auto& [k, v] : brick_segments) keys.push_back(k);
  std::sort(keys.begin(), keys.end());  // same order on every run
  auto unpack = [](uint64_t key) {
    return Eigen::Vector3i(int(key & (kAxisLimit - 1)), int((key >> 20) & (kAxisLimit - 1)), int(key >> 40));
  };

  // sample each brick's nodes; a brick whose centre is farther from the wall than its half
  // diagonal plus two cells (f is 1-Lipschitz) is wholly outside (dropped) or inside (flagged)
  constexpr int32_t kInside = -2;
  std::unordered_map<uint64_t, int32_t> brick_slot;
  std::vector<float> values;
  std::vector<uint64_t> sampled;
  const double half_diagonal = std::sqrt(3.0) * 0.5 * (kBrick - 1) * h;
  const float nudge = static_cast<float>(1e-9 * h);
  size_t inside_count = 0;
  for (const uint64_t key : keys) {
    const auto& list = brick_segments[key];
    const Eigen::Vector3i b = unpack(key);
    const Vector3d centre =
        node_position(b.x() * kBrick, b.y() * kBrick, b.z() * kBrick).array() + 0.5 * (kBrick - 1) * h;
    double f_centre = std::numeric_limits<double>::infinity();
    for (int si : list) f_centre = std::min(f_centre, segment_distance(segs[si], centre));
    if (f_centre > half_diagonal + 2.0 * h) continue;
    if (f_centre < -(half_diagonal + 2.0 * h)) {
      brick_slot[key] = kInside;
      ++inside_count;
      continue;
    }
    const size_t base = values.size();
    values.resize(base + kBrickNodes);
    for (int z = 0; z < kBrick; ++z)
      for (int y = 0; y < kBrick; ++y)
        for (int x = 0; x < kBrick; ++x) {
          const Vector3d p = node_position(b.x() * kBrick + x, b.y() * kBrick + y, b.z() * kBrick + z);
          double f = std::numeric_limits<double>::infinity();
          for (int si : list) f = std::min(f, segment_distance(segs[si], p));
          float v = static_cast<float>(f);
          // no vertex may land on a node: a zero sample counts as outside
          if (v == 0.0f) v = nudge;
          values[base + (z * kBrick + y) * kBrick + x] = v;
        }
    brick_slot[key] = static_cast<int32_t>(base / kBrickNodes);
    sampled.push_back(key);
  }
  const size_t list_bytes = [&] {
    size_t n = 0;
    for (const auto& [k, v] : brick_segments) n += v.capacity() * sizeof(int) + 64;
    return n;
  }();
  brick_segments = {};

  // a node's value: from its brick; a brick never sampled lies outside unless flagged inside
  const float outside = static_cast<float>(h), inside = -static_cast<float>(h);
  auto value_at = [&](int64_t i, int64_t j, int64_t k) -> float {
    const auto it = brick_slot.find(pack(i / kBrick, j / kBrick, k / kBrick));
    if (it == brick_slot.end()) return outside;
    if (it->second == kInside) return inside;
    return values[size_t(it->second) * kBrickNodes + ((k % kBrick) * kBrick + j % kBrick) * kBrick + i % kBrick];
  };

  // marching tetrahedra: one vertex per cut grid edge, shared through the edge's key
  const TetTable& table = tet_table();
  std::unordered_map<uint64_t, int> edge_vertex;
  std::array<int64_t, 3> corner_node[8];
  std::array<float, 8> f;
  auto vertex_on = [&](int c0, int c1) {
    if (c0 > c1) std::swap(c0, c1);  // Kuhn edges join corners c0 subset of c1: c0 is the lower node
    const auto& n0 = corner_node[c0];
    const uint64_t key = (pack(n0[0], n0[1], n0[2]) << 3) | uint64_t(c0 ^ c1);
    const auto [it, fresh] = edge_vertex.try_emplace(key, static_cast<int>(mesh.vertices_m.size()));
    if (fresh) {
      const auto& n1 = corner_node[c1];
      const double t = std::clamp(double(f[c0]) / (double(f[c0]) - double(f[c1])), 1e-4, 1.0 - 1e-4);
      const Vector3d p0 = node_position(n0[0], n0[1], n0[2]), p1 = node_position(n1[0], n1[1], n1[2]);
      mesh.vertices_m.push_back(p0 + t * (p1 - p0));
    }
    return it->second;
  };
  for (const uint64_t key : sampled) {
    const Eigen::Vector3i b = unpack(key);
    for (int z = 0; z < kBrick; ++z)
      for (int y = 0; y < kBrick; ++y)
        for (int x = 0; x < kBrick; ++x) {
          const int64_t i = b.x() * kBrick + x, j = b.y() * kBrick + y, k = b.z() * kBrick + z;
          int negative = 0;
          for (int c = 0; c < 8; ++c) {
            corner_node[c] = {i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)};
            f[c] = value_at(corner_node[c][0], corner_node[c][1], corner_node[c][2]);
            negative += f[c] < 0.0f;
          }
          if (negative == 0 || negative == 8) continue;
          for (const auto& tet : table.tets) {
            int in_mask = 0, n_in = 0;
            for (int v = 0; v < 4; ++v) {
              if (f[tet[v]] < 0.0f) {
                in_mask |= 1 << v;
                ++n_in;
              }
            }
            if (n_in == 0 || n_in == 4) continue;
            // an even permutation keeps the tetrahedron's positive orientation, which fixes the
            // winding: the lone inside (or outside) vertex first, or the two inside ones
            for (const auto& p : table.even_perms) {
              const bool in0 = in_mask >> p[0] & 1, in1 = in_mask >> p[1] & 1;
              const int c0 = tet[p[0]], c1 = tet[p[1]], c2 = tet[p[2]], c3 = tet[p[3]];
              if (n_in == 1 && in0) {
                mesh.triangles.push_back({vertex_on(c0, c1), vertex_on(c0, c2), vertex_on(c0, c3)});
              } else if (n_in == 3 && !in0) {
                mesh.triangles.push_back({vertex_on(c0, c1), vertex_on(c0, c3), vertex_on(c0, c2)});
              } else if (n_in == 2 && in0 && in1) {
                const int va = vertex_on(c0, c2), vb = vertex_on(c0, c3);
                const int vc = vertex_on(c1, c3), vd = vertex_on(c1, c2);
                mesh.triangles.push_back({va, vb, vc});
                mesh.triangles.push_back({va, vc, vd});
              } else {
                continue;
              }
              break;
            }
          }
        }
  }

  // closed inner shells (tiny pockets left between overlapping swept spheres, inward facing, so
  // of negative volume) are not lumen wall: they are dropped, which fills the pocket
  const size_t cavities = drop_inner_shells(mesh);

  if (stats) {
    stats->cavities_removed = cavities;
    stats->spacing_m = h;
    stats->segments = segs.size();
    stats->bricks_sampled = sampled.size();
    stats->bricks_inside = inside_count;
    stats->memory_bytes = values.capacity() * sizeof(float) + list_bytes + brick_slot.size() * 32 +
                          edge_vertex.size() * 32 + keys.capacity() * sizeof(uint64_t);
  }
  return mesh;
}

int count_components(const TriangleMesh& mesh) {
  const std::vector<int> label = vertex_components(mesh);
  std::vector<char> used(mesh.vertices_m.size(), 0);
  for (const auto& t : mesh.triangles) used[t[0]] = used[t[1]] = used[t[2]] = 1;
  int n = 0;
  for (size_t v = 0; v < label.size(); ++v) n += used[v] && label[v] == int(v);
  return n;
}

}  // namespace pcisim::anatomy
