#include "modeling/cta/coronary_clipping.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "modeling/cta/modeling_error.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

Vector3d physical(const ImageGrid& g, int64_t n) {
  const auto [i, j, k] = g.ijk(n);
  return g.physical_mm(Vector3d(double(i), double(j), double(k)));
}

// the voxel of largest distance within radius_mm of p (restricted to mask != 0), or -1
int64_t ridge_near(const FloatImage& dist, const Vector3d& p_mm, double radius_mm) {
  const ImageGrid& g = dist.grid;
  const Vector3d c = g.continuous_index(p_mm);
  const Vector3d r = Vector3d::Constant(radius_mm).cwiseQuotient(g.spacing_mm);
  int64_t best = -1;
  float best_d = 0;
  for (int64_t k = std::max<int64_t>(0, std::floor(c.z() - r.z()));
       k <= std::min<int64_t>(g.dims[2] - 1, std::ceil(c.z() + r.z())); ++k) {
    for (int64_t j = std::max<int64_t>(0, std::floor(c.y() - r.y()));
         j <= std::min<int64_t>(g.dims[1] - 1, std::ceil(c.y() + r.y())); ++j) {
      for (int64_t i = std::max<int64_t>(0, std::floor(c.x() - r.x()));
           i <= std::min<int64_t>(g.dims[0] - 1, std::ceil(c.x() + r.x())); ++i) {
        const int64_t n = g.index(i, j, k);
        if (dist.v[n] <= best_d) continue;
        if ((Vector3d(i, j, k) - c).cwiseProduct(g.spacing_mm).norm() > radius_mm) continue;
        best = n;
        best_d = dist.v[n];
      }
    }
  }
  return best;
}

// the ostium of a piece: it may touch the large lumen in several patches (contact voxels within 2
// voxels of one another): the aortic root, and a left atrial appendage or a chamber it runs
// beside, or the rim of the aorta it runs along (issue #30's family). The ostium's patch is where
// the vessel is widest (its trunk enters the root there: the patch's deepest voxel, by the
// lumen's distance map, within 0.25 mm of the deepest of all; a rim or a side contact is shallow),
// of those the patch nearest the aortic seed; in it, the voxel nearest the patch's centroid
int64_t ostium_voxel(const ImageGrid& g, const FloatImage& distance_mm, std::vector<int64_t> contact,
                     const Vector3d& seed_mm) {
  std::sort(contact.begin(), contact.end());
  std::vector<int> patch_of(contact.size(), -1);
  std::vector<std::vector<size_t>> patches;
  for (size_t first = 0; first < contact.size(); ++first) {
    if (patch_of[first] >= 0) continue;
    const int id = static_cast<int>(patches.size());
    patches.emplace_back(1, first);
    patch_of[first] = id;
    for (size_t t = 0; t < patches[id].size(); ++t) {
      const auto [i, j, k] = g.ijk(contact[patches[id][t]]);
      for (int dk = -2; dk <= 2; ++dk) {
        for (int dj = -2; dj <= 2; ++dj) {
          for (int di = -2; di <= 2; ++di) {
            if (!g.inside(i + di, j + dj, k + dk)) continue;
            const int64_t m = g.index(i + di, j + dj, k + dk);
            const auto at = std::lower_bound(contact.begin(), contact.end(), m);
            if (at == contact.end() || *at != m) continue;
            const size_t n = static_cast<size_t>(at - contact.begin());
            if (patch_of[n] >= 0) continue;
            patch_of[n] = id;
            patches[id].push_back(n);
          }
        }
      }
    }
  }
  std::vector<float> depth(patches.size(), 0);
  std::vector<double> to_seed(patches.size(), 1e300);
  for (size_t p = 0; p < patches.size(); ++p) {
    for (size_t n : patches[p]) {
      depth[p] = std::max(depth[p], distance_mm.v[contact[n]]);
      to_seed[p] = std::min(to_seed[p], (physical(g, contact[n]) - seed_mm).norm());
    }
  }
  const float deepest = *std::max_element(depth.begin(), depth.end());
  size_t pick = 0;
  for (size_t p = 0; p < patches.size(); ++p) {
    if (depth[p] >= deepest - 0.25f && (depth[pick] < deepest - 0.25f || to_seed[p] < to_seed[pick])) pick = p;
  }
  Vector3d centroid = Vector3d::Zero();
  for (size_t n : patches[pick]) centroid += physical(g, contact[n]);
  centroid /= double(patches[pick].size());
  int64_t best = contact[patches[pick].front()];
  for (size_t n : patches[pick]) {
    if ((physical(g, contact[n]) - centroid).squaredNorm() < (physical(g, best) - centroid).squaredNorm())
      best = contact[n];
  }
  return best;
}

}  // namespace

Clipping clip_to_coronaries(const LumenSegmentation& seg, const std::vector<Vector3d>& seeds_mm,
                            const ClippingOptions& o) {
  const ImageGrid& g = seg.mask.grid;
  Clipping out;
  out.distance_mm = distance_inside_mm(seg.mask, o.threads);

  // 1. the opening by a ball: core voxels deep enough, grown back by the same radius
  Mask core = Mask::zeros(g);
  for (size_t n = 0; n < core.v.size(); ++n) core.v[n] = out.distance_mm.v[n] >= o.big_radius_mm ? 0 : 1;
  // distance of every non-core voxel to the core (the core is the mask's "outside" here)
  const FloatImage to_core = distance_inside_mm(core, o.threads);
  out.large = Mask::zeros(g);
  const double reach = o.big_radius_mm + o.rim_mm + 0.5 * g.spacing_mm.minCoeff();
  for (size_t n = 0; n < core.v.size(); ++n) out.large.v[n] = seg.mask.v[n] && to_core.v[n] <= reach ? 1 : 0;
  core = Mask{};

  // the seed's place in the aorta: the deepest voxel near it
  const int64_t seed_ridge = ridge_near(out.distance_mm, seeds_mm[0], 10.0);
  if (seed_ridge < 0 || !out.large.v[seed_ridge]) {
    throw ModelingError(
        fmt::format("seed 1 at ({:.1f}, {:.1f}, {:.1f}) mm is not in a lumen wider than {:.1f} mm: put it inside the "
                    "ascending aorta",
                    seeds_mm[0].x(), seeds_mm[0].y(), seeds_mm[0].z(), 2 * o.big_radius_mm));
  }
  out.aorta_at_seed = {physical(g, seed_ridge), out.distance_mm.v[seed_ridge]};
  const double aortic_radius_mm = out.distance_mm.v[seed_ridge];

  // 2. thin pieces, 26-connected, with their contact on the large lumen
  const Neighbours26 nb(g.spacing_mm);
  std::vector<int32_t> piece_of(g.size(), -1);
  std::vector<int64_t> stack;
  std::vector<int64_t> seed_voxels;
  for (size_t s = 1; s < seeds_mm.size(); ++s) {
    const Vector3d c = g.continuous_index(seeds_mm[s]);
    const int64_t i = std::llround(c.x()), j = std::llround(c.y()), k = std::llround(c.z());
    if (g.inside(i, j, k)) seed_voxels.push_back(g.index(i, j, k));
  }
  int32_t next_id = 0;
  std::vector<size_t> dropped_sizes;  // beside out.dropped
  for (int64_t start = 0; start < g.size(); ++start) {
    if (!seg.mask.v[start] || out.large.v[start] || piece_of[start] >= 0) continue;
    CoronaryPiece piece;
    std::vector<int64_t> contact;
    piece_of[start] = next_id;
    stack.assign(1, start);
    while (!stack.empty()) {
      const int64_t n = stack.back();
      stack.pop_back();
      piece.voxels.push_back(n);
      const auto [i, j, k] = g.ijk(n);
      bool touches = false;
      for (int q = 0; q < 26; ++q) {
        const int64_t a = i + nb.d[q][0], b = j + nb.d[q][1], c = k + nb.d[q][2];
        if (!g.inside(a, b, c)) continue;
        const int64_t m = g.index(a, b, c);
        if (!seg.mask.v[m]) continue;
        if (out.large.v[m]) {
          touches = true;
        } else if (piece_of[m] < 0) {
          piece_of[m] = next_id;
          stack.push_back(m);
        }
      }
      if (touches) contact.push_back(n);
    }
    ++next_id;
    const bool seeded =
        std::any_of(seed_voxels.begin(), seed_voxels.end(), [&](int64_t s) { return piece_of[s] == next_id - 1; });
    const Vector3d first = physical(g, start);
    auto drop = [&](const std::string& why) {
      if (piece.voxels.size() >= 50) {
        out.dropped.push_back(fmt::format("{} voxels near ({:.1f}, {:.1f}, {:.1f}) mm: {}", piece.voxels.size(),
                                          first.x(), first.y(), first.z(), why));
        dropped_sizes.push_back(piece.voxels.size());
      }
    };
    if (contact.empty()) {
      drop("not attached to the aorta or a chamber");
      continue;
    }
    piece.ostium = ostium_voxel(g, out.distance_mm, contact, seeds_mm[0]);
    piece.ostium_mm = physical(g, piece.ostium);
    for (int64_t n : piece.voxels) piece.reach_mm = std::max(piece.reach_mm, (physical(g, n) - piece.ostium_mm).norm());
    const double from_seed_mm = (piece.ostium_mm - seeds_mm[0]).norm();
    float deepest = 0;
    for (int64_t n : piece.voxels) deepest = std::max(deepest, out.distance_mm.v[n]);
    if (!seeded && deepest < o.min_piece_radius_mm) {
      drop(fmt::format("nowhere more than {:.2f} mm from its edge: a rim, not a vessel", deepest));
      continue;
    }
    if (!seeded && piece.reach_mm < o.min_length_mm) {
      drop(fmt::format("reaches {:.1f} mm from its contact, under {:.1f} mm", piece.reach_mm, o.min_length_mm));
      continue;
    }
    // a tree is slender: its volume over its reach is the cross-section of a tube no wider than
    // max_tree_tube_radius_mm (a chamber whose contrast sits at the threshold is a sponge of
    // noise, thin everywhere, but fills its space)
    const double volume_mm3 = double(piece.voxels.size()) * g.spacing_mm.prod();
    const double tube_r_mm = std::sqrt(volume_mm3 / (M_PI * std::max(piece.reach_mm, 1e-9)));
    if (!seeded && tube_r_mm > o.max_tree_tube_radius_mm) {
      out.root_sponges += from_seed_mm <= o.max_ostium_distance_mm;
      drop(
          fmt::format("{:.0f} mm3 within {:.1f} mm of its contact, as much as a tube {:.1f} mm in radius: a chamber's "
                      "noisy contrast, not a vessel tree",
                      volume_mm3, piece.reach_mm, tube_r_mm));
      continue;
    }
    if (!seeded && from_seed_mm > o.max_ostium_distance_mm) {
      drop(fmt::format("attached {:.1f} mm from the aortic seed, beyond {:.1f} mm (a chamber, not the aortic root)",
                       from_seed_mm, o.max_ostium_distance_mm));
      continue;
    }
    const int64_t c = ridge_near(out.distance_mm, piece.ostium_mm, aortic_radius_mm + 5.0);
    piece.aortic_centre_mm = c >= 0 ? physical(g, c) : piece.ostium_mm;
    out.pieces.push_back(std::move(piece));
  }
  if (out.pieces.empty()) {
    // the largest pieces cut away and why: what a person looks at first
    std::vector<size_t> order(out.dropped.size());
    for (size_t n = 0; n < order.size(); ++n) order[n] = n;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return dropped_sizes[a] > dropped_sizes[b]; });
    std::string largest;
    for (size_t n = 0; n < std::min<size_t>(3, order.size()); ++n) largest += "; " + out.dropped[order[n]];
    out.none_found = fmt::format(
        "no coronary artery found: no thin contrast-filled vessel of at least {:.0f} mm leaves the aorta "
        "within {:.0f} mm of the seed (lumen HU {:.0f}..{:.0f}; {} thin pieces cut away{})",
        o.min_length_mm, o.max_ostium_distance_mm, seg.lower_hu, seg.upper_hu, out.dropped.size(),
        largest.empty() ? "" : ", the largest" + largest);
    if (o.throw_when_none) throw ModelingError(out.none_found);
    return out;
  }
  std::sort(out.pieces.begin(), out.pieces.end(),
            [](const CoronaryPiece& a, const CoronaryPiece& b) { return a.reach_mm > b.reach_mm; });

  // 3. the aorta: from below the ostia through the seed, then up the ridge of the distance map
  Vector3d root = Vector3d::Zero();
  for (const auto& p : out.pieces) root += p.aortic_centre_mm;
  root /= double(out.pieces.size());
  const Vector3d seed_c = out.aorta_at_seed.position_m;
  Vector3d axis = seed_c - root;
  if (axis.norm() < 1.0) axis = Vector3d(0, 0, 1);
  axis.normalize();
  std::vector<Vector3d> pts;
  const double span = (seed_c - root).norm();
  for (double s = -5.0; s <= span; s += 1.0) pts.push_back(root + s * axis);
  Vector3d p = seed_c, dir = axis;
  for (double s = 0; s < o.aorta_above_seed_mm; s += 2.0) {
    const int64_t c = ridge_near(out.distance_mm, p + 2.0 * dir, 0.25 * aortic_radius_mm + 1.0);
    if (c < 0 || out.distance_mm.v[c] < 0.5 * aortic_radius_mm) break;
    const Vector3d q = physical(g, c);
    if ((q - p).norm() < 0.5) break;
    dir = (0.5 * dir + 0.5 * (q - p).normalized()).normalized();
    p = q;
    pts.push_back(p);
  }
  for (const Vector3d& q : pts) {
    const Vector3d ci = g.continuous_index(q);
    const int64_t i = std::llround(ci.x()), j = std::llround(ci.y()), k = std::llround(ci.z());
    const double r = g.inside(i, j, k) ? out.distance_mm.v[g.index(i, j, k)] : 0.0;
    out.aorta.push_back({q, r > 0 ? r : aortic_radius_mm});
  }
  return out;
}

}  // namespace pcisim::modeling
