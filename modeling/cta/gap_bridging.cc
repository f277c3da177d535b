#include "modeling/cta/gap_bridging.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <queue>
#include <limits>
#include <span>

#include "realtime/percentile.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

Vector3d ijk_of(const ImageGrid& g, int64_t n) {
  const auto [i, j, k] = g.ijk(n);
  return Vector3d(double(i), double(j), double(k));
}

struct Piece {
  std::vector<int64_t> voxels;
  double length_mm = 0;
};

// region mask values: the region, candidate voxels already visited, the piece being checked
constexpr uint8_t kRegion = 1, kSeen = 2, kThisPiece = 3;
constexpr int kFaces[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

// the 26-connected pieces of contrast HU outside the region that look like vessels (their voxels
// are left marked kSeen)
std::vector<Piece> vessel_like_pieces(const anatomy::Volume& ct, double lower_hu, double upper_hu, Mask* region,
                                      const GapBridgingOptions& o) {
  const ImageGrid& g = region->grid;
  const double voxel_mm3 = g.spacing_mm.prod();
  const Neighbours26 nb(g.spacing_mm);
  auto candidate = [&](int64_t n) {
    if (region->v[n]) return false;
    const float h = ct.type == anatomy::VoxelType::kInt16 ? float(ct.hu_i16[n]) : ct.hu_f32[n];
    return h >= lower_hu && h <= upper_hu;
  };
  auto hu = [&](int64_t n) { return ct.type == anatomy::VoxelType::kInt16 ? float(ct.hu_i16[n]) : ct.hu_f32[n]; };
  std::vector<Piece> out;
  std::vector<int64_t> queue;
  for (int64_t n0 = 0; n0 < g.size(); ++n0) {
    if (!candidate(n0)) continue;
    queue.assign(1, n0);
    region->v[n0] = kSeen;
    // its outer neighbours, and how many of them are brighter than lumen (bone's cortex, calcium)
    // and how many neighbours its voxels have within it (solid lumen: most; noise strung
    // together through voxel corners: a few)
    int64_t shell = 0, bright = 0, inner = 0, interior = 0;
    for (size_t head = 0; head < queue.size(); ++head) {
      const auto [i, j, k] = g.ijk(queue[head]);
      // interior: all six face neighbours in the piece (visited, or a candidate the fill will reach)
      bool all_faces = true;
      for (const auto& f : kFaces) {
        const int64_t a = i + f[0], b = j + f[1], c = k + f[2];
        const int64_t m = g.inside(a, b, c) ? g.index(a, b, c) : -1;
        if (m < 0 || !(region->v[m] == kSeen || candidate(m))) all_faces = false;
      }
      interior += all_faces ? 1 : 0;
      for (const auto& d : nb.d) {
        const int64_t a = i + d[0], b = j + d[1], c = k + d[2];
        if (!g.inside(a, b, c)) continue;
        const int64_t m = g.index(a, b, c);
        if (region->v[m] == kSeen) {
          ++inner;
          continue;
        }
        if (!candidate(m)) {
          ++shell;
          bright += hu(m) > upper_hu ? 1 : 0;
          continue;
        }
        ++inner;
        region->v[m] = kSeen;
        queue.push_back(m);
      }
    }
    // too small to be min_length_mm of a vessel 0.5 mm in radius
    const double volume_mm3 = double(queue.size()) * voxel_mm3;
    if (volume_mm3 < M_PI * 0.25 * o.min_length_mm) continue;
    // marrow inside a bone's cortex, not a vessel in fat (a calcified plaque touches a small part)
    if (double(bright) > o.max_bright_shell * double(shell)) continue;
    if (double(inner) < o.min_mean_neighbours * double(queue.size())) continue;
    if (double(interior) < o.min_interior_fraction * double(queue.size())) continue;
    // its extent along its main axis (principal component of the voxel positions)
    Vector3d mean = Vector3d::Zero();
    for (int64_t n : queue) mean += g.physical_mm(ijk_of(g, n));
    mean /= double(queue.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int64_t n : queue) {
      const Vector3d r = g.physical_mm(ijk_of(g, n)) - mean;
      cov += r * r.transpose();
    }
    const Vector3d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(2);
    double lo = 1e300, hi = -1e300;
    for (int64_t n : queue) {
      const double s = (g.physical_mm(ijk_of(g, n)) - mean).dot(axis);
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
    const double length_mm = hi - lo;
    if (length_mm < o.min_length_mm) continue;
    // a vessel: its volume over its length is the cross-section of a tube no wider than max_radius_mm
    if (std::sqrt(volume_mm3 / (M_PI * length_mm)) > o.max_radius_mm) continue;
    out.push_back({queue, length_mm});
  }
  return out;
}

// the nearest pair (region voxel p, piece voxel q) within max_gap_mm: a search outward from the
// piece over the 26-neighbour graph (Dijkstra; its path lengths overestimate straight distances
// by at most ~8 %, so the search runs 10 % farther), on the box around the piece that the search
// can reach. False when the region is not that near.
bool nearest_region_voxel(const Mask& region, const Piece& piece, const Neighbours26& nb, double max_gap_mm, int64_t* p,
                          int64_t* q) {
  const ImageGrid& g = region.grid;
  const double reach_mm = 1.1 * max_gap_mm;
  // the box: the piece's voxels' box grown by the reach
  std::array<int64_t, 3> lo{g.dims[0], g.dims[1], g.dims[2]}, hi{-1, -1, -1};
  for (int64_t n : piece.voxels) {
    const auto ijk = g.ijk(n);
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], ijk[a]), hi[a] = std::max(hi[a], ijk[a]);
  }
  std::array<int64_t, 3> dims;
  for (int a = 0; a < 3; ++a) {
    const int64_t r = static_cast<int64_t>(std::ceil(reach_mm / g.spacing_mm[a]));
    lo[a] = std::max<int64_t>(0, lo[a] - r);
    hi[a] = std::min<int64_t>(g.dims[a] - 1, hi[a] + r);
    dims[a] = hi[a] - lo[a] + 1;
  }
  const ImageGrid box = g.crop(lo, dims);
  auto to_box = [&](int64_t n) {
    const auto [i, j, k] = g.ijk(n);
    return box.index(i - lo[0], j - lo[1], k - lo[2]);
  };
  auto to_grid = [&](int64_t m) {
    const auto [i, j, k] = box.ijk(m);
    return g.index(i + lo[0], j + lo[1], k + lo[2]);
  };
  std::vector<float> dist(box.size(), std::numeric_limits<float>::infinity());
  std::vector<int32_t> source(box.size(), -1);  // the piece voxel (box index) each path starts from
  using Item = std::pair<float, int32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  for (int64_t n : piece.voxels) {
    const int32_t m = static_cast<int32_t>(to_box(n));
    dist[m] = 0;
    source[m] = m;
    open.push({0.0f, m});
  }
  while (!open.empty()) {
    const auto [d, m] = open.top();
    open.pop();
    if (d > dist[m]) continue;
    if (d > reach_mm) return false;
    if (region.v[to_grid(m)] == kRegion) {
      *p = to_grid(m);
      *q = to_grid(source[m]);
      return true;
    }
    const auto [i, j, k] = box.ijk(m);
    for (int s = 0; s < 26; ++s) {
      const int64_t a = i + nb.d[s][0], b = j + nb.d[s][1], c = k + nb.d[s][2];
      if (!box.inside(a, b, c)) continue;
      const int32_t x = static_cast<int32_t>(box.index(a, b, c));
      const float dx = d + static_cast<float>(nb.length_mm[s]);
      if (dx >= dist[x]) continue;
      dist[x] = dx;
      source[x] = source[m];
      open.push({dx, x});
    }
  }
  return false;
}

// how the set `in` looks within ball_mm of p: the share of the ball it fills and its centroid
struct BallLook {
  double fill = 0;
  Vector3d centroid_mm = Vector3d::Zero();
};

template <typename In>
BallLook look_around(const ImageGrid& g, const Vector3d& p_ijk, double ball_mm, In in) {
  BallLook out;
  int64_t inside = 0, total = 0;
  const Vector3d p_mm = g.physical_mm(p_ijk);
  const Vector3d r = (ball_mm / g.spacing_mm.array()).ceil().matrix();
  for (int64_t k = int64_t(p_ijk.z() - r.z()); k <= int64_t(p_ijk.z() + r.z()); ++k) {
    for (int64_t j = int64_t(p_ijk.y() - r.y()); j <= int64_t(p_ijk.y() + r.y()); ++j) {
      for (int64_t i = int64_t(p_ijk.x() - r.x()); i <= int64_t(p_ijk.x() + r.x()); ++i) {
        if (!g.inside(i, j, k)) continue;
        const Vector3d q_mm = g.physical_mm(Vector3d(i, j, k));
        if ((q_mm - p_mm).norm() > ball_mm) continue;
        ++total;
        if (!in(g.index(i, j, k))) continue;
        ++inside;
        out.centroid_mm += q_mm;
      }
    }
  }
  if (inside > 0) out.centroid_mm /= double(inside);
  out.fill = total > 0 ? double(inside) / double(total) : 1.0;
  return out;
}

// marks the voxels within radius_mm of the segment a-b (physical mm); returns how many were new
int64_t fill_cylinder(Mask* mask, const Vector3d& a_mm, const Vector3d& b_mm, double radius_mm) {
  const ImageGrid& g = mask->grid;
  const Vector3d ia = g.continuous_index(a_mm), ib = g.continuous_index(b_mm);
  const Vector3d r = (radius_mm / g.spacing_mm.array()).ceil().matrix();
  const Vector3d lo = ia.cwiseMin(ib) - r, hi = ia.cwiseMax(ib) + r;
  const Vector3d ab = b_mm - a_mm;
  int64_t added = 0;
  for (int64_t k = int64_t(std::floor(lo.z())); k <= int64_t(std::ceil(hi.z())); ++k) {
    for (int64_t j = int64_t(std::floor(lo.y())); j <= int64_t(std::ceil(hi.y())); ++j) {
      for (int64_t i = int64_t(std::floor(lo.x())); i <= int64_t(std::ceil(hi.x())); ++i) {
        if (!g.inside(i, j, k)) continue;
        const Vector3d q = g.physical_mm(Vector3d(i, j, k));
        const double t = std::clamp((q - a_mm).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
        if ((a_mm + t * ab - q).norm() > radius_mm) continue;
        uint8_t& v = mask->v[g.index(i, j, k)];
        added += v == 1 ? 0 : 1;
        v = 1;
      }
    }
  }
  return added;
}

}  // namespace

std::vector<Bridge> bridge_gaps(const anatomy::Volume& ct, double lower_hu, double upper_hu, Mask* region,
                                const GapBridgingOptions& o) {
  std::vector<Bridge> bridges;
  if (!o.enabled) return bridges;
  const ImageGrid& g = region->grid;
  auto hu = [&](int64_t n) { return ct.type == anatomy::VoxelType::kInt16 ? float(ct.hu_i16[n]) : ct.hu_f32[n]; };
  const Neighbours26 nb(g.spacing_mm);
  std::vector<Piece> pieces = vessel_like_pieces(ct, lower_hu, upper_hu, region, o);
  const double cos_max = std::cos(o.max_angle_deg * M_PI / 180.0);
  // the bridge must connect 26-wise: at least half a voxel's diagonal
  const double bridge_r = std::max(o.bridge_radius_mm, 0.5 * std::sqrt(3.0) * g.spacing_mm.maxCoeff());
  for (int pass = 0; pass < o.passes && !pieces.empty(); ++pass) {
    std::vector<Piece> left;
    bool joined = false;
    for (Piece& piece : pieces) {
      int64_t p = -1, q = -1;
      if (!nearest_region_voxel(*region, piece, nb, o.max_gap_mm, &p, &q)) {
        left.push_back(std::move(piece));
        continue;
      }
      const Vector3d p_ijk = ijk_of(g, p), p_mm = g.physical_mm(p_ijk);
      const Vector3d q_ijk = ijk_of(g, q), q_mm = g.physical_mm(q_ijk);
      const double gap_mm = (q_mm - p_mm).norm();
      const Vector3d u = (q_mm - p_mm) / std::max(gap_mm, 1e-9);
      // the region ends at p as a thin vessel, its voxels behind p
      const BallLook at_p = look_around(g, p_ijk, o.end_ball_mm, [&](int64_t n) { return region->v[n] == kRegion; });
      const Vector3d behind = p_mm - at_p.centroid_mm;
      const bool region_ends =
          gap_mm <= o.max_gap_mm && at_p.fill <= o.max_end_fill && behind.dot(u) >= cos_max * behind.norm();
      // the piece starts at q the same way, its voxels beyond q
      for (int64_t n : piece.voxels) region->v[n] = kThisPiece;
      const BallLook at_q = look_around(g, q_ijk, o.end_ball_mm, [&](int64_t n) { return region->v[n] == kThisPiece; });
      for (int64_t n : piece.voxels) region->v[n] = kSeen;
      const Vector3d beyond = at_q.centroid_mm - q_mm;
      const bool piece_starts = at_q.fill <= o.max_end_fill && beyond.dot(u) >= cos_max * beyond.norm();
      // the same contrast on both sides: a vessel beyond a stenosis fills as the vessel before it;
      // costal cartilage (~150 HU) or a vein does not
      // (the HU of each voxel's 3x3x3 neighbourhood, thresholded nowhere: a piece of voxels picked
      // by the threshold from tissue just below it has the tissue's mean, a lumen its own)
      auto local_mean = [&](int64_t n) {
        const auto [i, j, k] = g.ijk(n);
        double sum = 0;
        int count = 0;
        for (int c = -1; c <= 1; ++c)
          for (int b = -1; b <= 1; ++b)
            for (int a = -1; a <= 1; ++a)
              if (g.inside(i + a, j + b, k + c)) sum += hu(g.index(i + a, j + b, k + c)), ++count;
        return static_cast<float>(sum / count);
      };
      std::vector<float> end_hu, piece_hu;
      const Vector3d r = (o.end_ball_mm / g.spacing_mm.array()).ceil().matrix();
      for (int64_t k = int64_t(p_ijk.z() - r.z()); k <= int64_t(p_ijk.z() + r.z()); ++k)
        for (int64_t j = int64_t(p_ijk.y() - r.y()); j <= int64_t(p_ijk.y() + r.y()); ++j)
          for (int64_t i = int64_t(p_ijk.x() - r.x()); i <= int64_t(p_ijk.x() + r.x()); ++i)
            if (g.inside(i, j, k) && region->v[g.index(i, j, k)] == kRegion)
              end_hu.push_back(local_mean(g.index(i, j, k)));
      for (int64_t n : piece.voxels) piece_hu.push_back(local_mean(n));
      // NaN when the end ball is empty: then not the same contrast
      const double piece_p90 = realtime::percentile_in_place(std::span<float>(piece_hu), 0.9);
      const double end_p90 = realtime::percentile_in_place(std::span<float>(end_hu), 0.9);
      const bool same_contrast =
          piece_p90 >= o.min_contrast_ratio * end_p90 && piece_p90 <= end_p90 / o.min_contrast_ratio;
      if (!region_ends || !piece_starts || !same_contrast) {
        left.push_back(std::move(piece));
        continue;
      }
      // join: the bridge, then the piece
      Bridge b;
      b.from_mm = p_mm;
      b.to_mm = q_mm;
      b.gap_mm = gap_mm;
      b.piece_length_mm = piece.length_mm;
      b.voxels_added = fill_cylinder(region, p_mm, q_mm, bridge_r);
      for (int64_t n : piece.voxels) {
        b.voxels_added += region->v[n] == kRegion ? 0 : 1;
        region->v[n] = kRegion;
      }
      bridges.push_back(b);
      joined = true;
    }
    if (!joined) break;
    pieces = std::move(left);
  }
  // only the region stays marked
  for (auto& v : region->v) v = v == kRegion ? 1 : 0;
  return bridges;
}

}  // namespace pcisim::modeling
