#include "modeling/evaluation/lumen_scores.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include <Eigen/Geometry>

#include "modeling/evaluation/closest_point_bvh.h"

namespace pcisim::modeling {

using anatomy::TriangleMesh;
using anatomy::VesselTree;
using Eigen::Vector3d;

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

struct WeightedDistance {
  double d_m, area_m2;
};

// each triangle cut into strips parallel to its longest edge, each strip into pieces, both about
// spacing_m across (a thin triangle gets one row, not a grid); a point at each piece's middle
// standing for the piece's share of its strip's area
template <class Visit>
void sample_surface(const TriangleMesh& mesh, double spacing_m, Visit&& visit) {
  const int nv = static_cast<int>(mesh.vertices_m.size());
  for (const auto& t : mesh.triangles) {
    for (int v : t) {
      if (v < 0 || v >= nv) throw std::invalid_argument("score_lumen: a triangle names a missing vertex");
    }
    // a-b the longest edge, c the apex
    std::array<Vector3d, 3> q = {mesh.vertices_m[t[0]], mesh.vertices_m[t[1]], mesh.vertices_m[t[2]]};
    int longest = 0;
    for (int e = 1; e < 3; ++e) {
      if ((q[(e + 1) % 3] - q[e]).squaredNorm() > (q[(longest + 1) % 3] - q[longest]).squaredNorm()) longest = e;
    }
    const Vector3d &a = q[longest], &b = q[(longest + 1) % 3], &c = q[(longest + 2) % 3];
    const double base = (b - a).norm(), area = 0.5 * (b - a).cross(c - a).norm();
    const double height = base > 0 ? 2 * area / base : 0.0;
    const int rows = std::max(1, static_cast<int>(std::ceil(height / spacing_m)));
    for (int j = 0; j < rows; ++j) {
      // the strip between heights j/rows and (j+1)/rows, cut across at its middle height y
      const double y = (j + 0.5) / rows, strip = 2 * area / rows * (1 - y);
      const Vector3d left = a + y * (c - a), right = b + y * (c - b);
      const int pieces = std::max(1, static_cast<int>(std::ceil(base * (1 - y) / spacing_m)));
      for (int i = 0; i < pieces; ++i) visit(left + (i + 0.5) / pieces * (right - left), strip / pieces);
    }
  }
}

// the area-weighted q-quantile: the smallest distance with at least q of the weight at or below it
double weighted_quantile(std::vector<WeightedDistance> v, double q) {
  if (v.empty()) return kNan;
  std::sort(v.begin(), v.end(), [](const auto& x, const auto& y) { return x.d_m < y.d_m; });
  double total = 0;
  for (const auto& x : v) total += x.area_m2;
  double acc = 0;
  for (const auto& x : v) {
    acc += x.area_m2;
    if (acc >= q * total) return x.d_m;
  }
  return v.back().d_m;
}

// voxels set in sparse 8x8x8 blocks: one 64-bit word per z layer of a block
class SparseVoxels {
 public:
  explicit SparseVoxels(double voxel_m) : h_(voxel_m) {}

  // sets every voxel whose centre lies in the frustum from (a, ra) to (b, rb) or in the balls
  // at its ends
  void add_rounded_cone(const Vector3d& a, double ra, const Vector3d& b, double rb) {
    ra = std::max(ra, 0.0);
    rb = std::max(rb, 0.0);
    const Vector3d lo = (a.array() - ra).min(b.array() - rb), hi = (a.array() + ra).max(b.array() + rb);
    std::array<int64_t, 3> i0, i1;
    for (int k = 0; k < 3; ++k) {
      // voxel centres sit at (i + 1/2) h
      i0[k] = static_cast<int64_t>(std::ceil(lo[k] / h_ - 0.5));
      i1[k] = static_cast<int64_t>(std::floor(hi[k] / h_ - 0.5));
      if (i1[k] < i0[k]) return;
      if (std::abs(i0[k] >> 3) >= kBlockRange || std::abs(i1[k] >> 3) >= kBlockRange) {
        throw std::invalid_argument("dice_of_trees: the trees reach too far for this voxel size");
      }
    }
    const Vector3d d = b - a;
    const double len2 = d.squaredNorm(), ra2 = ra * ra, rb2 = rb * rb;
    auto inside = [&](const Vector3d& p) {
      const Vector3d v = p - a;
      const double v2 = v.squaredNorm();
      if (v2 <= ra2 || (p - b).squaredNorm() <= rb2) return true;
      if (!(len2 > 0)) return false;
      const double t = v.dot(d) / len2;
      if (t < 0 || t > 1) return false;
      const double r = ra + t * (rb - ra);
      return v2 - t * t * len2 <= r * r;
    };
    for (int64_t bz = i0[2] >> 3; bz <= i1[2] >> 3; ++bz) {
      for (int64_t by = i0[1] >> 3; by <= i1[1] >> 3; ++by) {
        for (int64_t bx = i0[0] >> 3; bx <= i1[0] >> 3; ++bx) {
          Block* block = nullptr;
          for (int64_t z = std::max(i0[2], bz * 8); z <= std::min(i1[2], bz * 8 + 7); ++z) {
            for (int64_t y = std::max(i0[1], by * 8); y <= std::min(i1[1], by * 8 + 7); ++y) {
              for (int64_t x = std::max(i0[0], bx * 8); x <= std::min(i1[0], bx * 8 + 7); ++x) {
                if (!inside(Vector3d(x + 0.5, y + 0.5, z + 0.5) * h_)) continue;
                if (!block) block = &blocks_[key(bx, by, bz)];
                (*block)[z - bz * 8] |= uint64_t{1} << ((y - by * 8) * 8 + (x - bx * 8));
              }
            }
          }
        }
      }
    }
  }

  int64_t count() const {
    int64_t n = 0;
    for (const auto& [k, block] : blocks_) {
      for (uint64_t w : block) n += std::popcount(w);
    }
    return n;
  }

  int64_t count_common(const SparseVoxels& other) const {
    int64_t n = 0;
    for (const auto& [k, block] : blocks_) {
      const auto it = other.blocks_.find(k);
      if (it == other.blocks_.end()) continue;
      for (int z = 0; z < 8; ++z) n += std::popcount(block[z] & it->second[z]);
    }
    return n;
  }

 private:
  using Block = std::array<uint64_t, 8>;
  static constexpr int64_t kBlockRange = int64_t{1} << 20;
  static uint64_t key(int64_t bx, int64_t by, int64_t bz) {
    return (uint64_t(bx + kBlockRange) << 42) | (uint64_t(by + kBlockRange) << 21) | uint64_t(bz + kBlockRange);
  }
  double h_;
  std::unordered_map<uint64_t, Block> blocks_;
};

bool is_excluded(const std::string& name, const std::vector<std::string>& exclude) {
  return std::find(exclude.begin(), exclude.end(), name) != exclude.end();
}

// a tree's lumen as rounded cones between consecutive points, each branch joined to its parent
void voxelise(const VesselTree& tree, const std::vector<std::string>& exclude, SparseVoxels* out) {
  const int nb = static_cast<int>(tree.branches.size());
  for (const auto& br : tree.branches) {
    if (br.points.empty() || is_excluded(br.name, exclude)) continue;
    if (br.parent >= 0 && br.parent < nb && !is_excluded(tree.branches[br.parent].name, exclude)) {
      const auto& pp = tree.branches[br.parent].points;
      if (br.parent_point >= 0 && br.parent_point < static_cast<int>(pp.size())) {
        const auto& q = pp[br.parent_point];
        out->add_rounded_cone(q.position_m, q.radius_m, br.points[0].position_m, br.points[0].radius_m);
      }
    }
    // a branch of one point is a ball
    const size_t n = br.points.size();
    for (size_t i = 0; i == 0 || i + 1 < n; ++i) {
      const auto& p = br.points[i];
      const auto& q = br.points[std::min(i + 1, n - 1)];
      out->add_rounded_cone(p.position_m, p.radius_m, q.position_m, q.radius_m);
    }
  }
}

}  // namespace

LumenScores score_lumen(const TriangleMesh& reference, const TriangleMesh& extracted, double sample_spacing_m) {
  if (!(sample_spacing_m > 0)) throw std::invalid_argument("score_lumen: sample_spacing_m must be > 0");
  LumenScores out;
  if (reference.triangles.empty() || extracted.triangles.empty()) {
    out.mean_mm = out.hausdorff95_mm = out.max_mm = kNan;
    out.reference_to_extracted_mean_mm = out.extracted_to_reference_mean_mm = kNan;
    return out;
  }
  const TriangleSet ref_set(reference.vertices_m, reference.triangles);
  const TriangleSet ext_set(extracted.vertices_m, extracted.triangles);
  std::vector<WeightedDistance> all;
  // one direction: the weighted mean distance from from's samples to to's triangles
  auto directed = [&](const TriangleMesh& from, const TriangleSet& to) {
    double sum = 0, area = 0;
    int guess = -1;  // consecutive samples lie close together: the last nearest triangle prunes
    sample_surface(from, sample_spacing_m, [&](const Vector3d& p, double w) {
      const double d = to.distance(p, &guess);
      all.push_back({d, w});
      sum += w * d;
      area += w;
    });
    return std::pair{sum, area};
  };
  const auto [sum_re, area_r] = directed(reference, ext_set);
  const auto [sum_er, area_e] = directed(extracted, ref_set);
  out.reference_to_extracted_mean_mm = area_r > 0 ? 1e3 * sum_re / area_r : kNan;
  out.extracted_to_reference_mean_mm = area_e > 0 ? 1e3 * sum_er / area_e : kNan;
  out.mean_mm = area_r + area_e > 0 ? 1e3 * (sum_re + sum_er) / (area_r + area_e) : kNan;
  out.max_mm = 0;
  for (const auto& x : all) out.max_mm = std::max(out.max_mm, 1e3 * x.d_m);
  out.samples = static_cast<int>(all.size());
  out.hausdorff95_mm = 1e3 * weighted_quantile(std::move(all), 0.95);
  return out;
}

double dice_of_trees(const VesselTree& a, const VesselTree& b, double voxel_m,
                     const std::vector<std::string>& exclude) {
  if (!(voxel_m > 0)) throw std::invalid_argument("dice_of_trees: voxel_m must be > 0");
  SparseVoxels va(voxel_m), vb(voxel_m);
  voxelise(a, exclude, &va);
  voxelise(b, exclude, &vb);
  const int64_t na = va.count(), nb = vb.count();
  if (na + nb == 0) return kNan;
  return 2.0 * static_cast<double>(va.count_common(vb)) / static_cast<double>(na + nb);
}

}  // namespace pcisim::modeling
