#include "anatomy/phantom/phantom_cta.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include <fmt/format.h>

#include "anatomy/phantom/coronary_phantom.h"
#include "anatomy/phantom/thorax_phantom.h"
#include "anatomy/volume/gaussian_blur.h"
#include "anatomy/volume/parallel_for.h"

#ifdef PCISIM_HAVE_JSON
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "anatomy/case/case_folder.h"
#include "anatomy/vessel/vessel_tree_json.h"
#include "anatomy/volume/volume_io.h"
#endif

namespace pcisim::anatomy {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

// Contrast and tissue values (HU) of a coronary CTA, the ranges the draws below keep to:
// - aorta and left heart 300..550: the SCCT guidelines ask for >= 250 HU in the coronaries and
//   report 300..450 HU as typical aortic-root enhancement after a bolus-tracked injection
//   (Abbara et al., J Cardiovasc Comput Tomogr 2016);
// - right heart 100..400: earlier or later in the bolus than the left heart, and diluted by
//   unenhanced caval inflow (same source; saline chaser protocols aim at a lower right heart);
// - coronary enhancement falls distally by a few HU per cm ("transluminal attenuation
//   gradient", about -5..-25 HU/10 mm in healthy arteries: Steigner et al., Int J Cardiovasc
//   Imaging 2010; Choi et al., JACC Cardiovasc Imaging 2011);
// - enhanced myocardium 40..100 and epicardial fat -100 (Buzug, Computed Tomography, 2008,
//   table 1.1; Radiopaedia, "Hounsfield unit");
// - calcified plaque well above 130 HU (the Agatston threshold) and several hundred HU in CTA,
//   700..1200 here (Agatston et al., JACC 1990; Radiopaedia, "coronary artery calcium score");
// - cardiac veins in the arterial phase 150..250, less enhanced than the arteries beside them
//   (the contrast has not yet come round through the capillaries).
constexpr double kLumenFloorHu = 250;

// seeded draws without std distributions (their output differs between standard libraries)
class Draw {
 public:
  explicit Draw(uint32_t seed) : rng_(seed ^ 0x85ebca6bu) {}
  // uniform in [0, 1)
  double u01() { return static_cast<double>(rng_() >> 8) / double(1u << 24); }
  double between(double lo, double hi) { return lo + (hi - lo) * u01(); }
  bool chance(double p) { return u01() < p; }

 private:
  std::mt19937 rng_;
};

// splitmix64's output function: a bijective 64-bit mix
uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// splitmix64: a fast, seeded stream for the noise, one per slice (so threads agree). Each
// slice's start is hashed: streams started at neighbouring states would be shifted copies of
// each other (correlated noise between slices).
struct SplitMix {
  uint64_t s;
  uint64_t next() { return mix64(s += 0x9e3779b97f4a7c15ull); }
};

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

std::vector<double> arc_lengths(const std::vector<CenterlinePoint>& pts) {
  std::vector<double> s(pts.size(), 0.0);
  for (size_t i = 1; i < pts.size(); ++i) s[i] = s[i - 1] + (pts[i].position_m - pts[i - 1].position_m).norm();
  return s;
}

int index_at(const std::vector<double>& arc, double s) {
  const auto it = std::lower_bound(arc.begin(), arc.end(), s);
  if (it == arc.end()) return static_cast<int>(arc.size()) - 1;
  const int i = static_cast<int>(it - arc.begin());
  return (i > 0 && s - arc[i - 1] < arc[i] - s) ? i - 1 : i;
}

Vector3d tangent(const std::vector<CenterlinePoint>& pts, size_t i) {
  const size_t a = i > 0 ? i - 1 : 0, b = std::min(pts.size() - 1, i + 1);
  return (pts[b].position_m - pts[a].position_m).normalized();
}

// beside the vessel along the heart's surface: perpendicular to the tangent and to the radial
// direction from the heart centre (the origin)
Vector3d lateral(const Vector3d& p, const Vector3d& t) {
  const Vector3d c = t.cross(p.normalized());
  return c.norm() > 1e-9 ? c.normalized() : Vector3d::Zero();
}

double distance_to_polyline(const std::vector<CenterlinePoint>& pts, const Vector3d& p) {
  double best = 1e300;
  for (size_t i = 0; i + 1 < pts.size(); ++i) {
    const Vector3d a = pts[i].position_m, ab = pts[i + 1].position_m - a;
    const double u = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-18), 0.0, 1.0);
    best = std::min(best, (p - a - u * ab).norm());
  }
  return best;
}

void drop_leaf(VesselTree* tree, const std::string& name) {
  const int id = tree->find(name);
  if (id < 0) return;
  for (const auto& b : tree->branches) {
    if (b.parent == id) return;  // not a leaf
  }
  tree->branches.erase(tree->branches.begin() + id);
  for (auto& b : tree->branches) {
    if (b.parent > id) --b.parent;
  }
}

// a primitive the partial-volume painter draws; priority stent > lumen > plaque > vein > chamber >
// background. A bloom (max_rule) takes no part in the priority: where it reaches, the value is the
// larger of its own and what the others gave (a calcium's blooming brightens what it covers).
enum class Kind { kStent = 0, kLumen = 1, kPlaque = 2, kVein = 3, kChamber = 4 };
constexpr int kNoKind = 5;
struct Prim {
  Kind kind;
  // capsule (rounded cone) a -> b, radii ra, rb, HU ha, hb along it
  Vector3d a, b;
  double ra = 0, rb = 0, ha = 0, hb = 0;
  // ellipsoid: inside when |m (p - a)| <= 1; min_semi for the conservative voxel tests
  Matrix3d m;
  double min_semi = 0;
  Vector3d lo, hi;  // bounding box (mm)
  bool is_ellipsoid = false;
  bool max_rule = false;
};

Prim capsule(Kind kind, const Vector3d& a, const Vector3d& b, double ra, double rb, double ha, double hb) {
  Prim p{kind, a, b, ra, rb, ha, hb, Matrix3d::Zero(), 0, {}, {}};
  const double r = std::max(ra, rb);
  p.lo = a.cwiseMin(b) - Vector3d::Constant(r);
  p.hi = a.cwiseMax(b) + Vector3d::Constant(r);
  return p;
}

Prim ellipsoid(const Vector3d& c, const Vector3d& semi, const Matrix3d& axes, double hu) {
  Prim p{Kind::kPlaque, c, c, 0, 0, hu, hu, Matrix3d::Zero(), semi.minCoeff(), {}, {}, true};
  p.m = semi.cwiseInverse().asDiagonal() * axes.transpose();
  // the box of a rotated ellipsoid: half-extent along world axis e is |diag(semi) axes^T e|
  const Matrix3d s = semi.asDiagonal() * axes.transpose();
  for (int d = 0; d < 3; ++d) {
    const double h = s.col(d).norm();
    p.lo[d] = c[d] - h;
    p.hi[d] = c[d] + h;
  }
  return p;
}

// (signed distance-like value at q, HU there); for a capsule the distance from the axis minus
// the local radius, for an ellipsoid (|m (q - c)| - 1) * min_semi (a lower bound on |distance|
// only where it is used with a margin)
inline bool inside(const Prim& p, const Vector3d& q, double* hu) {
  if (p.is_ellipsoid) {
    *hu = p.ha;
    return (p.m * (q - p.a)).squaredNorm() <= 1.0;
  }
  const Vector3d ab = p.b - p.a, aq = q - p.a;
  const double u = std::clamp(aq.dot(ab) / std::max(ab.squaredNorm(), 1e-18), 0.0, 1.0);
  const double r = p.ra + (p.rb - p.ra) * u;
  *hu = p.ha + (p.hb - p.ha) * u;
  return (aq - u * ab).squaredNorm() <= r * r;
}

// > margin: the voxel is outside; < -margin: wholly inside; between: partly
inline double clearance(const Prim& p, const Vector3d& q, double* hu) {
  if (p.is_ellipsoid) {
    *hu = p.ha;
    return ((p.m * (q - p.a)).norm() - 1.0) * p.min_semi;
  }
  const Vector3d ab = p.b - p.a, aq = q - p.a;
  const double u = std::clamp(aq.dot(ab) / std::max(ab.squaredNorm(), 1e-18), 0.0, 1.0);
  *hu = p.ha + (p.hb - p.ha) * u;
  return (aq - u * ab).norm() - (p.ra + (p.rb - p.ra) * u);
}

// paints the primitives into a float volume (identity direction) with partial volume: voxels
// near a surface get the mean of 4x4x4 sub-samples, each the value of the highest-priority
// primitive holding it or the voxel's background
void paint_partial_volume(std::vector<float>* hu, const std::array<int64_t, 3>& dims, const Vector3d& origin,
                          const Vector3d& spacing, const std::vector<Prim>& prims, int threads) {
  constexpr int kCell = 8, kSub = 4;
  std::array<int64_t, 3> cells;
  for (int d = 0; d < 3; ++d) cells[d] = (dims[d] + kCell - 1) / kCell;
  // (cell, primitive) pairs, sorted by cell: each cell lists the primitives whose box meets it
  std::vector<std::pair<int64_t, int>> pairs;
  for (size_t n = 0; n < prims.size(); ++n) {
    int64_t lo[3], hi[3];
    bool empty = false;
    for (int d = 0; d < 3; ++d) {
      // voxels whose cube meets the box, clamped before the casts
      const double nd = static_cast<double>(dims[d]);
      const double l = std::clamp(std::ceil((prims[n].lo[d] - origin[d]) / spacing[d] - 0.5), -1.0, nd);
      const double h = std::clamp(std::floor((prims[n].hi[d] - origin[d]) / spacing[d] + 0.5), -1.0, nd);
      lo[d] = std::max<int64_t>(0, static_cast<int64_t>(l));
      hi[d] = std::min<int64_t>(dims[d] - 1, static_cast<int64_t>(h));
      if (hi[d] < lo[d]) empty = true;
      lo[d] /= kCell;
      hi[d] /= kCell;
    }
    if (empty) continue;
    for (int64_t k = lo[2]; k <= hi[2]; ++k) {
      for (int64_t j = lo[1]; j <= hi[1]; ++j) {
        for (int64_t i = lo[0]; i <= hi[0]; ++i) pairs.push_back({i + cells[0] * (j + cells[1] * k), int(n)});
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<size_t> starts;
  for (size_t n = 0; n < pairs.size(); ++n) {
    if (n == 0 || pairs[n].first != pairs[n - 1].first) starts.push_back(n);
  }
  starts.push_back(pairs.size());

  const double margin = 0.5 * spacing.norm() * 1.5;  // half the voxel diagonal, with room for cones
  parallel_for(static_cast<int64_t>(starts.size()) - 1, threads, [&](int64_t c) {
    const int64_t cell = pairs[starts[c]].first;
    const int64_t ci = cell % cells[0], cj = (cell / cells[0]) % cells[1], ck = cell / (cells[0] * cells[1]);
    std::vector<const Prim*> near, blooms;
    for (int64_t k = ck * kCell; k < std::min(dims[2], (ck + 1) * kCell); ++k) {
      for (int64_t j = cj * kCell; j < std::min(dims[1], (cj + 1) * kCell); ++j) {
        for (int64_t i = ci * kCell; i < std::min(dims[0], (ci + 1) * kCell); ++i) {
          const Vector3d q = origin + spacing.cwiseProduct(Vector3d(double(i), double(j), double(k)));
          near.clear();
          blooms.clear();
          int whole = kNoKind;  // the best kind holding the whole voxel
          double whole_hu = 0;
          int best_partial = kNoKind;
          for (size_t n = starts[c]; n < starts[c + 1]; ++n) {
            const Prim& p = prims[pairs[n].second];
            double v;
            const double d = clearance(p, q, &v);
            if (d > margin) continue;
            if (p.max_rule) {
              blooms.push_back(&p);
              continue;
            }
            const int kind = static_cast<int>(p.kind);
            if (d < -margin) {
              if (kind < whole) whole = kind, whole_hu = v;
            } else {
              near.push_back(&p);
              best_partial = std::min(best_partial, kind);
            }
          }
          float& out = (*hu)[i + dims[0] * (j + dims[1] * k)];
          if (whole < kNoKind && whole <= best_partial && blooms.empty()) {
            out = static_cast<float>(whole_hu);
            continue;
          }
          if (near.empty() && blooms.empty()) continue;
          const double background = out;
          double sum = 0;
          for (int c2 = 0; c2 < kSub; ++c2) {
            for (int b2 = 0; b2 < kSub; ++b2) {
              for (int a2 = 0; a2 < kSub; ++a2) {
                const Vector3d f((a2 + 0.5) / kSub - 0.5, (b2 + 0.5) / kSub - 0.5, (c2 + 0.5) / kSub - 0.5);
                const Vector3d qs = q + spacing.cwiseProduct(f);
                int best = whole;
                double value = whole < kNoKind ? whole_hu : background;
                for (const Prim* p : near) {
                  const int kind = static_cast<int>(p->kind);
                  if (kind >= best) continue;
                  double v;
                  if (inside(*p, qs, &v)) best = kind, value = v;
                }
                for (const Prim* p : blooms) {
                  double v;
                  if (inside(*p, qs, &v)) value = std::max(value, v);
                }
                sum += value;
              }
            }
          }
          out = static_cast<float>(sum / (kSub * kSub * kSub));
        }
      }
    }
  });
}

// the signed permutation behind a direction matrix: index axis a runs along physical axis
// axis_of[a], forwards when sign_of[a] > 0
void signed_permutation(const Matrix3d& d, int axis_of[3], int sign_of[3]) {
  bool row_used[3] = {false, false, false};
  for (int a = 0; a < 3; ++a) {
    int found = -1;
    for (int r = 0; r < 3; ++r) {
      const double x = d(r, a);
      if (x == 0.0) continue;
      if ((x != 1.0 && x != -1.0) || found >= 0) found = -2;
      if (found == -1) found = r;
    }
    if (found < 0 || row_used[found]) {
      throw std::invalid_argument("PhantomCtaSpec.direction: expected a signed permutation matrix");
    }
    row_used[found] = true;
    axis_of[a] = found;
    sign_of[a] = d(found, a) > 0 ? 1 : -1;
  }
}

void validate_spec(const PhantomCtaSpec& s) {
  const char* axis = "xyz";
  int64_t voxels = 1;
  for (int a = 0; a < 3; ++a) {
    if (s.dims[a] < 1 || s.dims[a] > kMaxPhantomCtaDim)
      throw std::invalid_argument(fmt::format("PhantomCtaSpec.dims: expected 1..{} voxels along {}, got {}",
                                              kMaxPhantomCtaDim, axis[a], s.dims[a]));
    voxels *= s.dims[a];  // at most 4096^3: no overflow
    if (!(s.spacing_mm[a] >= kMinPhantomCtaVoxelMm && s.spacing_mm[a] <= kMaxPhantomCtaVoxelMm))
      throw std::invalid_argument(fmt::format("PhantomCtaSpec.spacing_mm: expected {} to {} mm along {}, got {}",
                                              kMinPhantomCtaVoxelMm, kMaxPhantomCtaVoxelMm, axis[a], s.spacing_mm[a]));
    const double extent_mm = static_cast<double>(s.dims[a]) * s.spacing_mm[a];
    if (extent_mm > kMaxPhantomCtaExtentMm)
      throw std::invalid_argument(fmt::format(
          "PhantomCtaSpec.dims x spacing_mm: expected a field of view of at most {} mm along {}, got {} x {} = {} mm",
          kMaxPhantomCtaExtentMm, axis[a], s.dims[a], s.spacing_mm[a], extent_mm));
  }
  if (voxels > kMaxPhantomCtaVoxels)
    throw std::invalid_argument(fmt::format("PhantomCtaSpec.dims: expected at most {} voxels, got {} x {} x {} = {}",
                                            kMaxPhantomCtaVoxels, s.dims[0], s.dims[1], s.dims[2], voxels));
  if (!(s.noise_sigma_hu >= 0) || !std::isfinite(s.noise_sigma_hu)) {
    throw std::invalid_argument("PhantomCtaSpec.noise_sigma_hu: expected >= 0");
  }
  if (!(s.blur_sigma_mm >= 0 && s.blur_sigma_mm <= kMaxPhantomCtaBlurMm))
    throw std::invalid_argument(fmt::format("PhantomCtaSpec.blur_sigma_mm: expected 0 to {} mm, got {}",
                                            kMaxPhantomCtaBlurMm, s.blur_sigma_mm));
  if (!(s.stenosis_fraction < 1.0) || std::isnan(s.stenosis_fraction)) {
    throw std::invalid_argument("PhantomCtaSpec.stenosis_fraction: expected < 1");
  }
  // a pin: unset (NaN) or inside the family's range, and only on a family member
  auto pin_in = [&s](const char* name, double v, double lo, double hi) {
    if (!std::isnan(v) && !s.family)
      throw std::invalid_argument(fmt::format("PhantomCtaSpec.pins.{}: pins a family draw, but family is false", name));
    if (!std::isnan(v) && !(v >= lo && v <= hi))
      throw std::invalid_argument(
          fmt::format("PhantomCtaSpec.pins.{}: expected {} to {} (or NaN: drawn), got {}", name, lo, hi, v));
  };
  pin_in("contrast_hu_proximal", s.pins.contrast_hu_proximal, 300, 550);
  pin_in("fade_hu_per_mm", s.pins.fade_hu_per_mm, 0.5, 3);
  pin_in("myocardium_hu", s.pins.myocardium_hu, 40, 150);
  pin_in("rv_hu", s.pins.rv_hu, 40, 400);
  pin_in("rv_wall_mm", s.pins.rv_wall_mm, 2, 5);
  pin_in("vein_hu", s.pins.vein_hu, 150, 300);
  if (s.pins.open_valve != -1 && !s.family)
    throw std::invalid_argument("PhantomCtaSpec.pins.open_valve: pins a family draw, but family is false");
  if (s.pins.open_valve < -1 || s.pins.open_valve > 1)
    throw std::invalid_argument(
        fmt::format("PhantomCtaSpec.pins.open_valve: expected -1 (drawn), 0 or 1, got {}", s.pins.open_valve));
  if (s.threads < 0 || s.threads > kMaxPhantomCtaThreads)
    throw std::invalid_argument(fmt::format("PhantomCtaSpec.threads: expected 0..{} (0: every core), got {}",
                                            kMaxPhantomCtaThreads, s.threads));
}

// the heart frame of the coronary phantom and the thorax painter (docs/anatomy.md): columns
// anterior, left, base
Matrix3d heart_frame() {
  const Vector3d base = Vector3d(-0.45, 0.35, 0.82).normalized();
  const Vector3d anterior = (Vector3d(0, -1, 0) - base.dot(Vector3d(0, -1, 0)) * base).normalized();
  Matrix3d heart;
  heart.col(0) = anterior;
  heart.col(1) = base.cross(anterior);
  heart.col(2) = base;
  return heart;
}

// ---- the family's draws (PhantomCtaSpec::family) ----

// a branch's direction over its first `s_mm`: the chord from its first point
Vector3d chord(const std::vector<CenterlinePoint>& pts, double s_mm) {
  const auto arc = arc_lengths(pts);
  return (pts[index_at(arc, s_mm)].position_m - pts.front().position_m).normalized();
}

double lad_lcx_angle_deg(const VesselTree& tree) {
  const int lad = tree.find("LAD"), lcx = tree.find("LCx");
  if (lad < 0 || lcx < 0) return 0;
  const double c = chord(tree.branches[lad].points, 5).dot(chord(tree.branches[lcx].points, 5));
  return std::acos(std::clamp(c, -1.0, 1.0)) / kDeg;
}

// the branch and every branch below it
std::vector<int> subtree(const VesselTree& tree, int root) {
  std::vector<int> out{root};
  for (size_t n = 0; n < out.size(); ++n) {
    for (size_t b = 0; b < tree.branches.size(); ++b) {
      if (tree.branches[b].parent == out[n]) out.push_back(static_cast<int>(b));
    }
  }
  return out;
}

// the least gap between the lumens of two sets of branches (mm), points within `skip_mm` of
// `near_mm` left out (a fork the two sets share)
double lumen_gap_mm(const VesselTree& tree, const std::vector<int>& a, const std::vector<int>& b,
                    const Vector3d& near_mm, double skip_mm) {
  double gap = 1e300;
  for (int i : a) {
    for (const auto& p : tree.branches[i].points) {
      if ((p.position_m - near_mm).norm() < skip_mm) continue;
      for (int j : b) {
        for (const auto& q : tree.branches[j].points) {
          if ((q.position_m - near_mm).norm() < skip_mm) continue;
          gap = std::min(gap, (p.position_m - q.position_m).norm() - p.radius_m - q.radius_m);
        }
      }
    }
  }
  return gap;
}

// the LAD-LCx angle drawn over 36..112 deg, the range Sun et al. measured on 50 coronary CTAs
// (Heart Res Open J 3(1), 2016: 72.9 +- 19.4 deg; Moon et al., PLoS ONE 13(9), 2018: mean 63 deg
// on 201). Each daughter's whole subtree is turned rigidly by half the change about the heart's
// normal at the fork, its points then put back at their distance from the heart's centre (on the
// epicardial shell); a change that brings any lumen within 2 mm of another tree's is halved (up
// to three times, then none). Heart-centred mm, before the pose.
void vary_bifurcation(VesselTree* tree, double target_deg) {
  const int lad = tree->find("LAD"), lcx = tree->find("LCx");
  if (lad < 0 || lcx < 0) return;
  const Vector3d fork = tree->branches[lcx].points.front().position_m;
  const Vector3d n = fork.normalized();
  const Vector3d a = chord(tree->branches[lad].points, 5), b = chord(tree->branches[lcx].points, 5);
  const double sign = a.cross(b).dot(n) >= 0 ? 1.0 : -1.0;  // turning the LCx by +sign widens
  const std::vector<int> lad_tree = subtree(*tree, lad), lcx_tree = subtree(*tree, lcx);
  std::vector<int> others;
  for (size_t o = 0; o < tree->branches.size(); ++o) {
    const int id = static_cast<int>(o);
    if (tree->branches[o].name == "aorta" || tree->branches[o].name == "LM") continue;
    if (std::find(lad_tree.begin(), lad_tree.end(), id) == lad_tree.end() &&
        std::find(lcx_tree.begin(), lcx_tree.end(), id) == lcx_tree.end())
      others.push_back(id);
  }
  double change = (target_deg - lad_lcx_angle_deg(*tree)) * kDeg;
  for (int attempt = 0; attempt < 4; ++attempt, change *= 0.5) {
    VesselTree turned = *tree;
    auto turn = [&](const std::vector<int>& ids, double angle) {
      const Eigen::AngleAxisd r(angle, n);
      for (int id : ids) {
        for (auto& p : turned.branches[id].points) {
          const double radius = p.position_m.norm();
          p.position_m = (r * (p.position_m - fork) + fork).normalized() * radius;
        }
      }
    };
    turn(lcx_tree, sign * change / 2);
    turn(lad_tree, -sign * change / 2);
    if (lumen_gap_mm(turned, lad_tree, lcx_tree, fork, 8.0) < 2.0) continue;
    std::vector<int> both = lad_tree;
    both.insert(both.end(), lcx_tree.begin(), lcx_tree.end());
    if (!others.empty() && lumen_gap_mm(turned, both, others, fork, 8.0) < 2.0) continue;
    *tree = std::move(turned);
    return;
  }
}

// a small side branch: from point `at` of `parent`, leaving it at `angle_deg` (on the side
// `side`), walking on the epicardial shell (the distance from the heart's centre of its first
// point) with a constant turn, `length_mm` long; radii set after the pose
std::vector<CenterlinePoint> side_branch_walk(const std::vector<CenterlinePoint>& parent, int at, double angle_deg,
                                              double side, double turn_per_mm, double length_mm) {
  constexpr double kStep = 0.5;
  Vector3d p = parent[at].position_m;
  const double shell = p.norm();
  Vector3d n = p.normalized();
  const Vector3d along = parent[at + 1].position_m - parent[at - 1].position_m;
  Vector3d t = (along - n * n.dot(along)).normalized();
  t = Eigen::AngleAxisd(side * angle_deg * kDeg, n) * t;
  std::vector<CenterlinePoint> pts;
  const int steps = static_cast<int>(std::lround(length_mm / kStep));
  for (int i = 0; i <= steps; ++i) {
    pts.push_back({p, 0.5});
    p = (p + kStep * t).normalized() * shell;
    n = p.normalized();
    t = Eigen::AngleAxisd(turn_per_mm * kStep, n) * t;
    t = (t - n * n.dot(t)).normalized();
  }
  return pts;
}

// 2..4 small side branches (septal, diagonal, marginal, right-ventricular twigs: the tree's
// smallest vessels, tapering to 0.5 mm radius) off the LAD, LCx, RCA, D1 and OM1, clear of every
// other lumen by 1.5 mm; named SB1.. (heart-centred mm, before the pose). Returns their ids.
std::vector<int> add_side_branches(VesselTree* tree, Draw& draw) {
  std::vector<int> added;
  const int count = 2 + std::min(2, static_cast<int>(draw.u01() * 3));
  const char* parents[] = {"LAD", "LCx", "RCA", "D1", "OM1"};
  for (int tries = 0; tries < 60 && static_cast<int>(added.size()) < count; ++tries) {
    const int parent = tree->find(parents[static_cast<int>(draw.u01() * 5) % 5]);
    const double unit = draw.u01(), angle = draw.between(35, 80), side = draw.chance(0.5) ? 1.0 : -1.0;
    const double turn = draw.between(-1.0, 1.0) / 40.0, length = draw.between(15, 35);
    if (parent < 0) continue;
    const auto& pts = tree->branches[parent].points;
    const auto arc = arc_lengths(pts);
    const double lo = tree->branches[parent].name == "RCA" ? 25.0 : 12.0, hi = arc.back() - 15.0;
    if (hi <= lo) continue;
    const int at = std::clamp(index_at(arc, lo + unit * (hi - lo)), 1, static_cast<int>(pts.size()) - 2);
    bool clear = true;
    for (const auto& c : tree->branches) {
      if (c.parent == parent && std::abs(arc[c.parent_point] - arc[at]) < 6.0) clear = false;
    }
    if (!clear) continue;
    const auto walk = side_branch_walk(pts, at, angle, side, turn, length);
    // its lumen (up to 0.8 mm) clear of every lumen by 1.5 mm, past its own first 3 mm
    for (size_t i = 0; i < walk.size() && clear; ++i) {
      if ((walk[i].position_m - pts[at].position_m).norm() < pts[at].radius_m + 3.0) continue;
      for (const auto& b : tree->branches) {
        if (b.name == "aorta") continue;
        for (const auto& q : b.points) {
          if ((walk[i].position_m - q.position_m).norm() < 0.8 + q.radius_m + 1.5) {
            clear = false;
            break;
          }
        }
        if (!clear) break;
      }
    }
    if (!clear) continue;
    added.push_back(static_cast<int>(tree->branches.size()));
    tree->branches.push_back({"SB" + std::to_string(added.size()), parent, at, walk});
  }
  return added;
}

// where the epicardial shell lies along unit direction u from the heart's centre, for a heart of
// this pose (rotation, scale, shape) whose shell is `shell_mm` before it
double shell_radius_mm(const Matrix3d& rotation, const Matrix3d& heart, double scale, const Vector3d& shape,
                       double shell_mm, const Vector3d& u) {
  const Vector3d v = (heart.transpose() * rotation.transpose() * u).cwiseQuotient(shape);
  return shell_mm * scale / v.norm();
}

}  // namespace

std::vector<Lesion> phantom_cta_lesions(const PhantomCta& phantom, double edge_stenosis_pct) {
  const PhantomCtaFacts& f = phantom.facts;
  const int b = phantom.truth.find(f.stenosis_branch);
  const double e = edge_stenosis_pct / 100.0;
  if (b < 0 || !(f.stenosis_fraction > e)) return {};
  // the narrowest point: the truth's point nearest the painted centre, its arc length
  const auto& pts = phantom.truth.branches[b].points;
  double best = std::numeric_limits<double>::infinity(), arc = 0.0, at = 0.0;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (i > 0) arc += 1e3 * (pts[i].position_m - pts[i - 1].position_m).norm();
    const double d = (1e3 * pts[i].position_m - f.stenosis_center_mm).norm();
    if (d < best) best = d, at = arc;
  }
  // a branch the grid cut short of the stenosis, or through it, has no whole lesion to report
  const double half_mm = 0.5 * f.stenosis_length_mm;
  if (!(best < 0.5) || at - half_mm < 0.0 || at + half_mm > arc) return {};
  Lesion l;
  l.branch = f.stenosis_branch;
  l.position_mm = at;
  l.reference_diameter_mm = 2.0 * f.stenosis_reference_radius_mm;
  l.minimal_lumen_diameter_mm = l.reference_diameter_mm * (1.0 - f.stenosis_fraction);
  l.diameter_stenosis_pct = 100.0 * f.stenosis_fraction;
  // r = r0 (1 - f (1 + cos(2 pi x / L)) / 2): narrowed by at least e where cos >= 2 e / f - 1
  l.length_mm = f.stenosis_length_mm / kPi * std::acos(std::clamp(2.0 * e / f.stenosis_fraction - 1.0, -1.0, 1.0));
  return {l};
}

double distance_to_painted_heart_mm(const PhantomCtaFacts& facts, const Eigen::Vector3d& p_mm) {
  const double r = kPhantomHeartRadiusMm * facts.heart_scale;
  if (facts.heart_axes_scale == Vector3d::Ones()) return std::abs((p_mm - facts.heart_center_mm).norm() - r);
  // a shaped heart (an ellipsoid): the first-order distance |g| / |grad g| of g = |y ./ a| - 1
  // (exact on a sphere; within a few per cent of the gap for the family's 0.9..1.1 shapes)
  const Vector3d a = r * facts.heart_axes_scale;
  const Vector3d y = heart_frame().transpose() * facts.heart_rotation.transpose() * (p_mm - facts.heart_center_mm);
  const Vector3d q = y.cwiseQuotient(a);
  const double qn = q.norm();
  if (qn < 1e-12) return a.minCoeff();
  const double grad = (q.cwiseQuotient(a) / qn).norm();
  return std::abs(qn - 1.0) / grad;
}

PhantomCtaSpec family_phantom_cta_spec(uint32_t seed) {
  // its own stream: the anatomy's draws (make_phantom_cta) do not move with these
  Draw draw(seed ^ 0x2545f491u);
  PhantomCtaSpec spec;
  spec.seed = seed;
  spec.family = true;
  const double in_plane = draw.between(0.3, 0.8), slice = draw.between(0.3, 0.8);
  spec.spacing_mm = Vector3d(in_plane, in_plane, slice);
  // a 512 matrix, widened where its field would be under 175 mm (the heart, its vessels and the
  // aortic root with room to spare); 140..160 mm along z
  const int64_t matrix = std::max<int64_t>(512, static_cast<int64_t>(std::ceil(175.0 / in_plane)));
  const double z_mm = draw.between(140, 160);
  spec.dims = {matrix, matrix, static_cast<int64_t>(std::ceil(z_mm / slice))};
  spec.noise_sigma_hu = draw.between(15, 45);
  spec.blur_sigma_mm = draw.between(0.3, 0.6);
  if (draw.chance(0.5)) spec.direction = Vector3d(1, 1, -1).asDiagonal();
  return spec;
}

PhantomCta make_phantom_cta(const PhantomCtaSpec& spec) {
  validate_spec(spec);
  int axis_of[3], sign_of[3];
  signed_permutation(spec.direction, axis_of, sign_of);
  const int threads =
      std::max(1, spec.threads > 0 ? spec.threads : static_cast<int>(std::thread::hardware_concurrency()));

  PhantomCta out;
  out.spec = spec;
  PhantomCtaFacts& facts = out.facts;
  Draw draw(spec.seed);
  // the family's own stream: the classic draws above and below stay as they were
  Draw fam(spec.seed ^ 0x68e31da4u);
  facts.family = spec.family;
  const Matrix3d heart = heart_frame();

  // the tree in mm (the fields say metres; here they hold mm until the end), heart centre at
  // the origin, patient LPS
  VesselTree tree = make_coronary_phantom({.seed = spec.seed});
  for (auto& b : tree.branches) {
    for (auto& p : b.points) {
      p.position_m *= 1000.0;
      p.radius_m *= 1000.0;
    }
  }

  // branch variation: D2 and OM2 are absent in some hearts
  for (const char* name : {"D2", "OM2"}) {
    if (draw.chance(0.35)) {
      drop_leaf(&tree, name);
      facts.dropped_branches.push_back(name);
    }
  }

  // the family: the LAD-LCx angle, small side branches, one tortuous trunk in 40 % of hearts
  // (coronary tortuosity as Li et al. define it, >= 3 bends of >= 45 deg along a trunk, was found
  // in 39 % of 1010 angiograms: PLoS ONE 6(8), 2011)
  std::vector<int> side_branches;
  if (spec.family) {
    vary_bifurcation(&tree, fam.between(36, 112));
    side_branches = add_side_branches(&tree, fam);
    for (int b : side_branches) facts.side_branches.push_back(tree.branches[b].name);
    const char* trunks[] = {"LAD", "LCx", "RCA"};
    const int pick = static_cast<int>(fam.u01() * 3) % 3;
    if (fam.chance(0.4)) facts.tortuous_branch = trunks[pick];
  }

  // extra tortuosity: a lateral sine along the heart's surface, faded in from the branch's start
  // (for the RCA, from where it leaves the aorta); a child carries its parent's displacement at
  // its branch point, faded out over 15 mm. The amplitude is capped so the curvature stays below
  // 1/8 mm^-1 (a short wavelength gets a small amplitude).
  {
    std::vector<std::vector<Vector3d>> disp(tree.branches.size());
    for (size_t b = 0; b < tree.branches.size(); ++b) {
      const auto& br = tree.branches[b];
      double wavelength = draw.between(10, 30);
      double amplitude = std::min(draw.between(0, 2), (1.0 / 8.0) * std::pow(wavelength / (2 * kPi), 2.0));
      const double phase = draw.between(-kPi, kPi);
      if (br.name == facts.tortuous_branch) {
        // a sine turns its direction by 2 atan(2 pi A / wavelength) between bends: A >= 0.07
        // wavelength turns it by >= 47 deg; the curvature cap as above
        wavelength = fam.between(24, 32);
        const double cap = 0.98 * (1.0 / 8.0) * std::pow(wavelength / (2 * kPi), 2.0);
        amplitude = fam.between(0.07 * wavelength, std::min(0.09 * wavelength, cap));
      }
      disp[b].assign(br.points.size(), Vector3d::Zero());
      if (br.name == "aorta" || br.name == "LM") continue;
      facts.tortuosity.push_back({br.name, amplitude, wavelength});
      const double s0 = br.name == "RCA" ? 18.0 : 0.0;
      const Vector3d carried = br.parent >= 0 ? disp[br.parent][br.parent_point] : Vector3d::Zero();
      const auto arc = arc_lengths(br.points);
      for (size_t i = 0; i < br.points.size(); ++i) {
        const double s = arc[i];
        const Vector3d side = lateral(br.points[i].position_m, tangent(br.points, i));
        disp[b][i] =
            carried * (1.0 - smoothstep(s / 15.0)) +
            side * (amplitude * std::sin(2 * kPi * (s - s0) / wavelength + phase) * smoothstep((s - s0) / 10.0));
      }
    }
    for (size_t b = 0; b < tree.branches.size(); ++b) {
      for (size_t i = 0; i < tree.branches[b].points.size(); ++i) tree.branches[b].points[i].position_m += disp[b][i];
    }
  }

  // the heart's pose: rotated +-15 deg about each axis (x, then y, then z) and scaled 0.9..1.1
  // about its centre; radii scaled 0.85..1.15 (the aorta's keeps its own)
  {
    Vector3d deg;  // one draw per statement: the order of a call's arguments is unspecified
    for (int d = 0; d < 3; ++d) deg[d] = draw.between(-15, 15);
    const Matrix3d r =
        (Eigen::AngleAxisd(deg.z() * kDeg, Vector3d::UnitZ()) * Eigen::AngleAxisd(deg.y() * kDeg, Vector3d::UnitY()) *
         Eigen::AngleAxisd(deg.x() * kDeg, Vector3d::UnitX()))
            .toRotationMatrix();
    facts.heart_rotation_deg = deg;
    facts.heart_rotation = r;
    facts.heart_scale = draw.between(0.9, 1.1);
    facts.radius_scale = draw.between(0.85, 1.15);
    // the family's hearts are ellipsoids: each axis of the heart frame scaled 0.9..1.1
    Matrix3d posed = r;
    if (spec.family) {
      for (int d = 0; d < 3; ++d) facts.heart_axes_scale[d] = fam.between(0.9, 1.1);
      posed = r * heart * facts.heart_axes_scale.asDiagonal() * heart.transpose();
    }
    for (auto& b : tree.branches) {
      for (auto& p : b.points) {
        p.position_m = facts.heart_scale * (posed * p.position_m);
        if (b.name != "aorta") p.radius_m *= facts.radius_scale;
      }
    }
    facts.lad_lcx_angle_deg = lad_lcx_angle_deg(tree);
    // the side branches taper from at most 0.8 mm (and 3/4 of the parent's) to 0.5 mm (or keep
    // the start's radius where that is under 0.5 mm)
    for (int b : side_branches) {
      auto& br = tree.branches[b];
      const double r0 = std::min(0.8, 0.75 * tree.branches[br.parent].points[br.parent_point].radius_m);
      const double r1 = std::min(0.5, r0);
      for (size_t i = 0; i < br.points.size(); ++i)
        br.points[i].radius_m = r0 + (r1 - r0) * static_cast<double>(i) / static_cast<double>(br.points.size() - 1);
    }
  }

  // contrast timing
  facts.aorta_hu = facts.contrast_hu_proximal = draw.between(300, 550);
  facts.lv_hu = facts.aorta_hu - draw.between(0, 30);
  facts.la_hu = facts.aorta_hu - draw.between(0, 40);
  facts.rv_hu = draw.between(100, 400);
  facts.ra_hu = std::clamp(facts.rv_hu + draw.between(-50, 50), 100.0, 400.0);
  facts.fade_hu_per_mm = draw.between(0.5, 2.0);
  facts.lumen_floor_hu = kLumenFloorHu;
  facts.myocardium_hu = draw.between(40, 100);
  facts.fat_sleeve_mm = draw.between(1.5, 3.0);
  facts.vein_hu = draw.between(150, 250);
  if (spec.family) {
    // the family widens what a scan shows: myocardium 40..150 HU (late or dense enhancement), a
    // steeper distal fall-off (to 3 HU/mm), the right heart from unenhanced (a saline chaser) to
    // enhanced, veins up to 300 HU (a later phase), the aortic valve open or closed, the right
    // ventricle's free wall 2..5 mm (normal RV free wall: 3-5 mm; Radiopaedia "right ventricle") with
    // a fuller cavity that reaches it
    facts.myocardium_hu = fam.between(40, 150);
    facts.fade_hu_per_mm = fam.between(0.5, 3.0);
    facts.rv_hu = fam.between(40, 400);
    facts.ra_hu = std::clamp(facts.rv_hu + fam.between(-50, 50), 40.0, 400.0);
    facts.vein_hu = fam.between(150, 300);
    facts.open_valve = fam.chance(0.7);
    facts.rv_wall_mm = fam.between(2, 5);
    Vector3d rv_semi;  // one draw per statement
    rv_semi.x() = fam.between(19, 23);
    rv_semi.y() = fam.between(26, 29);
    rv_semi.z() = fam.between(30, 33);
    facts.rv_semi_mm = rv_semi;
    // a test's pins (every draw above was made: the rest of the phantom is as without them)
    const PhantomCtaSpec::FamilyPins& pin = spec.pins;
    auto pinned = [](double* value, double to) {
      if (!std::isnan(to)) *value = to;
    };
    pinned(&facts.contrast_hu_proximal, pin.contrast_hu_proximal);
    if (!std::isnan(pin.contrast_hu_proximal)) {
      facts.lv_hu += pin.contrast_hu_proximal - facts.aorta_hu;
      facts.la_hu += pin.contrast_hu_proximal - facts.aorta_hu;
      facts.aorta_hu = pin.contrast_hu_proximal;
    }
    pinned(&facts.fade_hu_per_mm, pin.fade_hu_per_mm);
    pinned(&facts.myocardium_hu, pin.myocardium_hu);
    if (!std::isnan(pin.rv_hu)) facts.rv_hu = facts.ra_hu = pin.rv_hu;
    pinned(&facts.rv_wall_mm, pin.rv_wall_mm);
    pinned(&facts.vein_hu, pin.vein_hu);
    if (pin.open_valve >= 0) facts.open_valve = pin.open_valve == 1;
  }

  const int aorta_id = tree.find("aorta");
  const auto& aorta = tree.branches[aorta_id].points;
  const double aorta_r = aorta.front().radius_m;
  auto children_near = [&](int branch, double s, double half, const std::vector<double>& arc) {
    for (const auto& c : tree.branches) {
      if (c.parent == branch && std::abs(arc[c.parent_point] - s) < half) return true;
    }
    return false;
  };

  // the radii before the stenosis (the vein and plaques sit against the healthy wall)
  std::vector<std::vector<double>> healthy(tree.branches.size());
  for (size_t b = 0; b < tree.branches.size(); ++b) {
    for (const auto& p : tree.branches[b].points) healthy[b].push_back(p.radius_m);
  }

  // the stenosis: LAD (proximal or mid) or RCA (past its aortic part), clear of branch points
  {
    const bool on_lad = draw.chance(0.5);
    const int b = tree.find(on_lad ? "LAD" : "RCA");
    auto& pts = tree.branches[b].points;
    const auto arc = arc_lengths(pts);
    const double len = draw.between(4, 8);
    const double drawn_fraction = draw.between(0.5, 0.8);
    const double fraction = spec.stenosis_fraction >= 0 ? spec.stenosis_fraction : drawn_fraction;
    const double lo = on_lad ? 10.0 : 25.0, hi = std::min(on_lad ? 45.0 : 65.0, arc.back() - len);
    double s = draw.between(lo, hi);
    for (int tries = 0; tries < 200 && children_near(b, s, len / 2 + 2.0, arc); ++tries) {
      s += 0.5;
      if (s > hi) s = lo;
    }
    const int centre = index_at(arc, s);
    s = arc[centre];
    for (size_t i = 0; i < pts.size(); ++i) {
      const double x = (arc[i] - s) / len;
      if (std::abs(x) <= 0.5) pts[i].radius_m *= 1.0 - fraction * 0.5 * (1.0 + std::cos(2 * kPi * x));
    }
    facts.stenosis_branch = tree.branches[b].name;
    facts.stenosis_arc_length_mm = s;
    facts.stenosis_fraction = fraction;
    facts.stenosis_length_mm = len;
    facts.stenosis_reference_radius_mm = healthy[b][centre];
    facts.stenosis_center_mm = pts[centre].position_m;
  }

  // the cardiac vein beside the LAD (the great cardiac vein) or the LCx, touching its healthy
  // outer wall, on the side where it meets no other branch
  std::vector<Prim> prims;
  {
    const bool on_lad = draw.chance(0.5);
    const int b = tree.find(on_lad ? "LAD" : "LCx");
    const auto& pts = tree.branches[b].points;
    const auto arc = arc_lengths(pts);
    const double rv = draw.between(1.0, 1.5);
    double len = draw.between(30, 50);
    len = std::min(len, arc.back() - 12.0);
    const double start_unit = draw.u01();
    const double side_sign = draw.chance(0.5) ? 1.0 : -1.0;
    std::vector<Vector3d> best;
    double best_clear = -1e300;
    double best_start = 0;
    // candidates: the drawn start and side first, then others; the first clear one wins
    for (int attempt = 0; attempt < 24; ++attempt) {
      const double start = 8.0 + std::fmod(start_unit + attempt * 0.382, 1.0) * std::max(0.0, arc.back() - len - 12.0);
      const double sign = (attempt % 2 == 0) ? side_sign : -side_sign;
      std::vector<Vector3d> path;
      for (size_t i = 0; i < pts.size(); ++i) {
        if (arc[i] < start || arc[i] > start + len) continue;
        const Vector3d side = lateral(pts[i].position_m, tangent(pts, i));
        path.push_back(pts[i].position_m + sign * (healthy[b][i] + rv) * side);
      }
      // clearance from every other branch's lumen
      double clear = 1e300;
      for (size_t o = 0; o < tree.branches.size(); ++o) {
        if (static_cast<int>(o) == b) continue;
        for (const auto& q : path) {
          for (const auto& cp : tree.branches[o].points) {
            clear = std::min(clear, (q - cp.position_m).norm() - cp.radius_m - rv);
          }
        }
      }
      if (clear > best_clear) best_clear = clear, best = path, best_start = start;
      if (clear > 1.0) break;
    }
    facts.vein_beside = tree.branches[b].name;
    facts.vein_start_mm = best_start;
    facts.vein_length_mm = len;
    facts.vein_radius_mm = rv;
    facts.vein_points_mm = best;
    for (size_t i = 0; i + 1 < best.size(); ++i) {
      prims.push_back(capsule(Kind::kVein, best[i], best[i + 1], rv, rv, facts.vein_hu, facts.vein_hu));
    }
  }

  // the family: veins crossing over arteries (a vein of 0.8..1.8 mm radius on the epicardium
  // passing over an artery at 45..90 deg, touching it where they cross), and the left atrial
  // appendage reaching round to the LCx (its tip 0.5..2.5 mm from the LCx's lumen, as the
  // appendage lies on the proximal circumflex; Radiopaedia, "left atrial appendage")
  const double shell_mm = kPhantomHeartRadiusMm + 1.5;
  auto shell_at = [&](const Vector3d& u) {
    return shell_radius_mm(facts.heart_rotation, heart, facts.heart_scale, facts.heart_axes_scale, shell_mm, u);
  };
  // the posed heart's point at heart-frame offset v (mm), heart centre at the origin
  auto heart_point = [&](const Vector3d& v) {
    return facts.heart_scale * (facts.heart_rotation * heart * facts.heart_axes_scale.cwiseProduct(v));
  };
  if (spec.family) {
    const int count = fam.chance(0.5) ? 2 : 1;
    const char* names[] = {"LAD", "LCx", "RCA", "D1", "OM1"};
    for (int tries = 0; tries < 80 && static_cast<int>(facts.crossing_veins.size()) < count; ++tries) {
      const int b = tree.find(names[static_cast<int>(fam.u01() * 5) % 5]);
      const double unit = fam.u01(), rv = fam.between(0.8, 1.8), angle = fam.between(45, 90);
      const double side = fam.chance(0.5) ? 1.0 : -1.0, length = fam.between(30, 50);
      if (b < 0) continue;
      const auto& pts = tree.branches[b].points;
      const auto arc = arc_lengths(pts);
      if (arc.back() < 25) continue;
      const int i = index_at(arc, 10 + unit * (arc.back() - 20));
      const Vector3d p = pts[i].position_m, u = p.normalized(), t = tangent(pts, i);
      const Vector3d d = (Eigen::AngleAxisd(side * angle * kDeg, u) * (t - u * u.dot(t))).normalized();
      // its centre (ra + rv) above the artery's where they cross, as high above the shell
      // elsewhere; lifted until no point of it is inside the artery (the artery rises and falls
      // about the shell near the crossing)
      double above = p.norm() - shell_at(u) + pts[i].radius_m + rv;
      PhantomCtaFacts::CrossingVein vein{tree.branches[b].name, rv, facts.vein_hu, angle, {}};
      for (int lift = 0; lift < 4; ++lift) {
        vein.points_mm.clear();
        for (double sv = -length / 2; sv <= length / 2 + 1e-9; sv += 0.5) {
          const double phi = sv / p.norm();
          const Vector3d dir = (u * std::cos(phi) + d * std::sin(phi)).normalized();
          vein.points_mm.push_back(dir * (shell_at(dir) + above));
        }
        double overlap = 0;
        for (const auto& v : vein.points_mm) {
          for (const auto& q : pts) overlap = std::max(overlap, q.radius_m + rv - (v - q.position_m).norm());
        }
        if (overlap < 0.02) break;
        above += overlap;
      }
      // clear of every other lumen by 0.5 mm, and of the crossed one away from the crossing
      bool clear = true;
      for (size_t o = 0; o < tree.branches.size() && clear; ++o) {
        if (tree.branches[o].name == "aorta") continue;
        for (const auto& q : tree.branches[o].points) {
          if (static_cast<int>(o) == b && (q.position_m - p).norm() < pts[i].radius_m + rv + 4.0) continue;
          for (const auto& v : vein.points_mm) {
            if ((v - q.position_m).norm() < q.radius_m + rv + 0.5) clear = false;
          }
          if (!clear) break;
        }
      }
      auto clear_of = [&](const std::vector<Vector3d>& other, double r_other) {
        for (const auto& v : vein.points_mm) {
          for (const auto& w : other) {
            if ((v - w).norm() < rv + r_other + 0.5) return false;
          }
        }
        return true;
      };
      clear = clear && clear_of(facts.vein_points_mm, facts.vein_radius_mm);
      for (const auto& other : facts.crossing_veins) clear = clear && clear_of(other.points_mm, other.radius_mm);
      if (!clear) continue;
      for (size_t n = 0; n + 1 < vein.points_mm.size(); ++n) {
        prims.push_back(capsule(Kind::kVein, vein.points_mm[n], vein.points_mm[n + 1], rv, rv, vein.hu, vein.hu));
      }
      facts.crossing_veins.push_back(std::move(vein));
    }

    const int lcx = tree.find("LCx");
    const Vector3d la = heart_point(Vector3d(-22, 8, 26));
    for (int tries = 0; lcx >= 0 && tries < 40 && facts.laa_gap_mm < 0; ++tries) {
      const double at = fam.between(6, 30), gap = fam.between(0.5, 2.5);
      const double r_tip = fam.between(4, 6), r_base = fam.between(7, 10);
      const auto& pts = tree.branches[lcx].points;
      const auto arc = arc_lengths(pts);
      const int i = index_at(arc, at);
      const Vector3d p = pts[i].position_m, u = (la - p).normalized();
      const Vector3d tip = p + u * (pts[i].radius_m + gap + r_tip);
      const Prim laa = capsule(Kind::kChamber, tip, la, r_tip, r_base, facts.la_hu, facts.la_hu);
      // its surface clear of every lumen by 0.4 mm at least; the gap recorded is the least over
      // them (often the LCx further along the groove, nearer than where the tip was aimed)
      double least = 1e300;
      for (const auto& br : tree.branches) {
        if (br.name == "aorta") continue;
        for (const auto& q : br.points) {
          double v;
          least = std::min(least, clearance(laa, q.position_m, &v) - q.radius_m);
        }
      }
      if (least < 0.4) continue;
      facts.laa_base_mm = la;
      facts.laa_tip_mm = tip;
      facts.laa_base_radius_mm = r_base;
      facts.laa_tip_radius_mm = r_tip;
      facts.laa_gap_mm = least;
      prims.push_back(laa);
    }
  }

  // calcified plaques: 1..3 ellipsoids in the wall of the LAD, LCx or RCA, their inner tip on
  // the lumen's surface (the widest within their length), clear of branch points, of the
  // stenosis, of each other, of the vein and of other branches' lumens
  std::vector<Prim> plaque_prims;
  {
    const int count = 1 + std::min(2, static_cast<int>(draw.u01() * 3));
    for (int n = 0; n < count; ++n) {
      const double which = draw.u01();
      const char* name = which < 0.4 ? "LAD" : (which < 0.7 ? "LCx" : "RCA");
      const double unit = draw.u01(), angle = draw.between(-kPi, kPi);
      Vector3d semi;
      semi.x() = draw.between(1.0, 2.0);
      semi.y() = draw.between(0.8, 1.2);
      semi.z() = draw.between(1.0, 1.5);
      const double hu = draw.between(700, 1200);
      const int b = tree.find(name);
      const auto& pts = tree.branches[b].points;
      const auto arc = arc_lengths(pts);
      const double lo = std::string(name) == "RCA" ? 22.0 : 8.0;
      const double hi = std::max(lo, std::min(std::string(name) == "LCx" ? 50.0 : 80.0, arc.back() - 6.0));
      double s = lo + unit * (hi - lo);
      // where the plaque sits for arc length `at`: centre and radial direction
      auto place = [&](double at, Vector3d* centre, Vector3d* radial, int* index) {
        const int i = index_at(arc, at);
        const Vector3d p = pts[i].position_m, t = tangent(pts, i);
        const Vector3d out_dir = (p.normalized() - t * t.dot(p.normalized())).normalized();
        *radial = std::cos(angle) * out_dir + std::sin(angle) * t.cross(out_dir);
        double wall = 0;
        for (size_t m = 0; m < pts.size(); ++m) {
          if (std::abs(arc[m] - arc[i]) <= semi.x() + 0.5) wall = std::max(wall, pts[m].radius_m);
        }
        *centre = p + (wall + semi.y()) * *radial;
        *index = i;
      };
      auto clash = [&](double at) {
        if (children_near(b, at, semi.x() + 2.0, arc)) return true;
        if (facts.vein_beside == name && at > facts.vein_start_mm - 4 &&
            at < facts.vein_start_mm + facts.vein_length_mm + 4)
          return true;
        for (const auto& p : facts.plaques) {
          if (p.branch == name && std::abs(p.arc_length_mm - at) < 5.0) return true;
        }
        if (facts.stenosis_branch == name &&
            std::abs(at - facts.stenosis_arc_length_mm) < 0.5 * facts.stenosis_length_mm + semi.x() + 1.0)
          return true;
        // clear of every other branch's lumen (a side branch running alongside near its origin)
        Vector3d centre, radial;
        int i;
        place(at, &centre, &radial, &i);
        for (size_t o = 0; o < tree.branches.size(); ++o) {
          if (static_cast<int>(o) == b || tree.branches[o].name == "aorta") continue;
          for (const auto& q : tree.branches[o].points) {
            if ((q.position_m - centre).norm() < q.radius_m + semi.maxCoeff() + 0.5) return true;
          }
        }
        return false;
      };
      for (int tries = 0; tries < 400 && clash(s); ++tries) {
        s += 0.5;
        if (s > hi) s = lo;
      }
      Vector3d c, radial;
      int i;
      place(s, &c, &radial, &i);
      const Vector3d t = tangent(pts, i);
      Matrix3d axes;
      axes.col(0) = t;
      axes.col(1) = radial;
      axes.col(2) = t.cross(radial);
      plaque_prims.push_back(ellipsoid(c, semi, axes, hu));
      facts.plaques.push_back({name, arc[i], c, semi, hu});
    }
  }

  // the family: calcium blooms (each plaque's halo, 0.3..0.8 mm wider, at 40..60 % of its HU over
  // what it covers: the scanner's blur and beam hardening make calcium look larger than it is,
  // narrowing the lumen beside it; Kalisz et al., RadioGraphics 36(4), 2016, "blooming artefact")
  // and, in half the hearts, a stent: rings of zig-zag struts of 0.08 mm radius against the lumen's
  // wall every 1.2 mm over 12..24 mm of the LAD, LCx or RCA, clear of the stenosis and the
  // plaques. The struts are painted at 50 000..90 000 HU so that after partial volume and blur
  // they show at 1 500 HU and more, as metal does in a CTA (its HU is clamped at 3 071): a thin
  // strut's peak after a blur of sigma is HU x its section / (2 pi sigma^2), so the value stands
  // for the metal's attenuation and its blooming together, not for a material
  std::vector<Prim> stent_prims;
  if (spec.family && spec.with_coronaries) {
    facts.bloom_mm = fam.between(0.3, 0.8);
    facts.bloom_fraction = fam.between(0.4, 0.6);
    const size_t n_plaques = spec.calcium_blooming ? plaque_prims.size() : 0;
    for (size_t n = 0; n < n_plaques; ++n) {
      const auto& pl = facts.plaques[n];
      Matrix3d axes = plaque_prims[n].m.transpose() * pl.semi_axes_mm.asDiagonal();  // back to unit axes
      for (int c = 0; c < 3; ++c) axes.col(c).normalize();
      Prim bloom = ellipsoid(pl.center_mm, pl.semi_axes_mm + Vector3d::Constant(facts.bloom_mm), axes,
                             facts.bloom_fraction * pl.hu);
      bloom.max_rule = true;
      plaque_prims.push_back(bloom);
    }
    if (fam.chance(0.5)) {
      const char* names[] = {"LAD", "LCx", "RCA"};
      for (int tries = 0; tries < 40 && facts.stent_branch.empty(); ++tries) {
        const int b = tree.find(names[static_cast<int>(fam.u01() * 3) % 3]);
        const double len = fam.between(12, 24), unit = fam.u01(), strut_hu = fam.between(50000, 90000);
        const double phase = fam.between(0, 2 * kPi);
        if (b < 0) continue;
        const auto& pts = tree.branches[b].points;
        const auto arc = arc_lengths(pts);
        const double lo = tree.branches[b].name == "RCA" ? 22.0 : 6.0, hi = arc.back() - len - 10.0;
        if (hi <= lo) continue;
        const double s0 = lo + unit * (hi - lo), s1 = s0 + len;
        bool clear = true;
        if (facts.stenosis_branch == tree.branches[b].name &&
            s1 + 3.0 > facts.stenosis_arc_length_mm - 0.5 * facts.stenosis_length_mm &&
            s0 - 3.0 < facts.stenosis_arc_length_mm + 0.5 * facts.stenosis_length_mm)
          clear = false;
        for (const auto& pl : facts.plaques) {
          if (pl.branch == tree.branches[b].name && pl.arc_length_mm > s0 - 5.0 && pl.arc_length_mm < s1 + 5.0)
            clear = false;
        }
        if (!clear) continue;
        constexpr double kStrut = 0.08, kRing = 1.2, kCrown = 0.45;
        constexpr int kPoints = 12;  // 6 crowns a ring
        auto strut_point = [&](double s, double angle) {
          const int i = index_at(arc, s);
          const Vector3d t = tangent(pts, i), p = pts[i].position_m;
          const Vector3d e1 = (p.normalized() - t * t.dot(p.normalized())).normalized(), e2 = t.cross(e1);
          return Vector3d(p + t * (s - arc[i]) +
                          (pts[i].radius_m + kStrut) * (std::cos(angle) * e1 + std::sin(angle) * e2));
        };
        std::vector<Vector3d> previous;
        for (double s = s0; s <= s1 + 1e-9; s += kRing) {
          std::vector<Vector3d> ring;
          for (int k = 0; k <= kPoints; ++k) {
            ring.push_back(strut_point(s + (k % 2 ? kCrown : -kCrown), phase + 2 * kPi * k / kPoints));
          }
          for (int k = 0; k < kPoints; ++k) {
            stent_prims.push_back(capsule(Kind::kStent, ring[k], ring[k + 1], kStrut, kStrut, strut_hu, strut_hu));
          }
          // three links to the ring before, from its crowns to these troughs
          for (int k = 1; k < kPoints && !previous.empty(); k += 4) {
            stent_prims.push_back(capsule(Kind::kStent, previous[k], ring[k - 1], kStrut, kStrut, strut_hu, strut_hu));
          }
          previous = std::move(ring);
        }
        facts.stent_branch = tree.branches[b].name;
        facts.stent_start_mm = s0;
        facts.stent_length_mm = len;
        facts.stent_strut_hu = strut_hu;
        facts.stent_center_mm = pts[index_at(arc, 0.5 * (s0 + s1))].position_m;
      }
    }
  }

  // the field of view: a cardiac CT is centred on the heart; here on the box of the heart (its
  // pericardium), the coronaries and the ascending aorta up to the aortic seed, with a seeded
  // shift (within the room the box leaves) so the heart is not always centred
  std::array<int64_t, 3> cdims;  // the canonical (identity-direction) grid, patient frame
  Vector3d cspacing;
  for (int a = 0; a < 3; ++a) {
    cdims[axis_of[a]] = spec.dims[a];
    cspacing[axis_of[a]] = spec.spacing_mm[a];
  }
  Vector3d hi = Vector3d::Constant(52.0 * facts.heart_scale * facts.heart_axes_scale.maxCoeff()), lo = -hi;
  const int seed_index = std::min<int>(50, static_cast<int>(tree.branches[aorta_id].points.size()) - 1);
  for (const auto& b : tree.branches) {
    for (size_t i = 0; i < b.points.size(); ++i) {
      if (b.name == "aorta" && static_cast<int>(i) > seed_index) break;
      const CenterlinePoint& p = b.points[i];
      lo = lo.cwiseMin(p.position_m - Vector3d::Constant(p.radius_m));
      hi = hi.cwiseMax(p.position_m + Vector3d::Constant(p.radius_m));
    }
  }
  Vector3d fov_center = 0.5 * (lo + hi);
  for (int d = 0; d < 3; ++d) {
    const double room = (cdims[d] - 1) * cspacing[d] - (hi[d] - lo[d]);
    fov_center[d] += draw.between(-1, 1) * std::clamp(room / 2 - 5.0, 0.0, 10.0);
  }
  // the heart's place in scanner coordinates (tables put the heart near the scanner's axis,
  // the patient's left, and a table-dependent distance along it)
  Vector3d drawn_offset;
  drawn_offset.x() = draw.between(-30, 30);
  drawn_offset.y() = -120 + draw.between(-30, 30);
  drawn_offset.z() = -150 + draw.between(-40, 40);
  const Vector3d offset = spec.scanner_frame ? drawn_offset : Vector3d::Zero();
  facts.heart_center_mm = offset;

  // the background: the thorax painter with the posed heart, enhanced chambers and aorta, the
  // outflow tract, fat sleeves and no lumens
  ThoraxPhantomSpec ts;
  ts.seed = spec.seed;
  ts.dims = cdims;
  ts.spacing_xyz_mm = cspacing;
  ts.center_mm = fov_center;
  ts.threads = threads;
  ts.hu.myocardium = facts.myocardium_hu;
  ts.heart_rotation = facts.heart_rotation;
  ts.heart_scale = facts.heart_scale;
  ts.lv_hu = facts.lv_hu;
  ts.la_hu = facts.la_hu;
  ts.rv_hu = facts.rv_hu;
  ts.ra_hu = facts.ra_hu;
  ts.aorta_hu = facts.aorta_hu;
  ts.lv_outflow = facts.open_valve;
  ts.heart_axes_scale = facts.heart_axes_scale;
  if (spec.family) {
    ts.rv_wall_mm = facts.rv_wall_mm;
    ts.rv_semi_mm = facts.rv_semi_mm;
  }
  ts.coronary_lumens = false;
  ts.coronary_fat_sleeve_mm = spec.with_coronaries ? facts.fat_sleeve_mm : 0.0;
  // chambers behind their walls: 4 mm of myocardium and fat between a chamber and the coronary shell
  ts.chamber_clearance_mm = 4.0;
  VesselTree tree_m = tree;
  for (auto& b : tree_m.branches) {
    for (auto& p : b.points) {
      p.position_m *= 1e-3;
      p.radius_m *= 1e-3;
    }
  }
  Volume canon = make_thorax_phantom(ts, tree_m);
  // the LV centre as the thorax painter places it (heart frame offset (-2, 14, -8) mm)
  facts.lv_center_mm = heart_point(Vector3d(-2, 14, -8)) + offset;

  // coronary lumens: HU fading with the path length from the ostium, one capsule per segment
  std::vector<std::vector<double>> path_mm(tree.branches.size());
  Vector3d lm_ostium = Vector3d::Zero(), rca_ostium = Vector3d::Zero();
  for (size_t b = 0; b < tree.branches.size(); ++b) {
    const auto& br = tree.branches[b];
    const auto arc = arc_lengths(br.points);
    path_mm[b].assign(br.points.size(), 0.0);
    if (br.name == "aorta") continue;
    if (br.parent == aorta_id) {
      // the ostium: the first point at the aortic wall
      size_t o = 0;
      while (o + 1 < br.points.size() && distance_to_polyline(aorta, br.points[o].position_m) < aorta_r) ++o;
      if (br.name == "LM") lm_ostium = br.points[o].position_m;
      if (br.name == "RCA") rca_ostium = br.points[o].position_m;
      for (size_t i = 0; i < br.points.size(); ++i) path_mm[b][i] = std::max(0.0, arc[i] - arc[o]);
    } else {
      const double base = path_mm[br.parent][br.parent_point];
      for (size_t i = 0; i < br.points.size(); ++i) path_mm[b][i] = base + arc[i];
    }
  }
  auto lumen_hu = [&](double d) {
    return std::max(facts.lumen_floor_hu, facts.contrast_hu_proximal - facts.fade_hu_per_mm * d);
  };
  if (spec.with_coronaries) {
    for (size_t b = 0; b < tree.branches.size(); ++b) {
      const auto& br = tree.branches[b];
      if (br.name == "aorta") continue;
      for (size_t i = 0; i + 1 < br.points.size(); ++i) {
        prims.push_back(capsule(Kind::kLumen, br.points[i].position_m, br.points[i + 1].position_m,
                                br.points[i].radius_m, br.points[i + 1].radius_m, lumen_hu(path_mm[b][i]),
                                lumen_hu(path_mm[b][i + 1])));
      }
    }
    prims.insert(prims.end(), plaque_prims.begin(), plaque_prims.end());
    prims.insert(prims.end(), stent_prims.begin(), stent_prims.end());
  }

  // to float; the partial-volume painter, the blur and the noise work on it
  std::vector<float> hu(canon.hu_i16.begin(), canon.hu_i16.end());
  std::vector<int16_t>().swap(canon.hu_i16);
  paint_partial_volume(&hu, cdims, canon.origin_mm, cspacing, prims, threads);
  if (spec.blur_sigma_mm > 0)
    gaussian_blur(&hu, cdims, Vector3d::Constant(spec.blur_sigma_mm).cwiseQuotient(cspacing), threads);
  if (spec.noise_sigma_hu > 0) {
    const uint64_t seed = 0x243f6a8885a308d3ull ^ (static_cast<uint64_t>(spec.seed) << 20);
    const int64_t slice = cdims[0] * cdims[1];
    parallel_for(cdims[2], threads, [&](int64_t k) {
      SplitMix rng{mix64(seed ^ mix64(static_cast<uint64_t>(k) + 1))};
      float* v = hu.data() + slice * k;
      for (int64_t n = 0; n < slice; n += 2) {
        // Box-Muller: two normal deviates from two uniforms
        const double u1 = (static_cast<double>(rng.next() >> 11) + 1.0) * 0x1.0p-53;
        const double u2 = static_cast<double>(rng.next() >> 11) * 0x1.0p-53;
        const double r = spec.noise_sigma_hu * std::sqrt(-2.0 * std::log(u1));
        v[n] += static_cast<float>(r * std::cos(2 * kPi * u2));
        if (n + 1 < slice) v[n + 1] += static_cast<float>(r * std::sin(2 * kPi * u2));
      }
    });
  }

  // the output grid: the canonical voxels re-ordered along the spec's direction; the physical
  // box is the same, moved by the scanner offset
  Vector3d origin = canon.origin_mm + offset;
  for (int a = 0; a < 3; ++a) {
    if (sign_of[a] < 0) origin[axis_of[a]] += (spec.dims[a] - 1) * spec.spacing_mm[a];
  }
  out.ct = Volume::make(spec.dims, spec.spacing_mm, origin, VoxelType::kInt16);
  out.ct.direction = spec.direction;
  {
    const int64_t cstride[3] = {1, cdims[0], cdims[0] * cdims[1]};
    int64_t step[3], base = 0;
    for (int a = 0; a < 3; ++a) {
      step[a] = sign_of[a] * cstride[axis_of[a]];
      if (sign_of[a] < 0) base += (spec.dims[a] - 1) * cstride[axis_of[a]];
    }
    parallel_for(spec.dims[2], threads, [&](int64_t k) {
      for (int64_t j = 0; j < spec.dims[1]; ++j) {
        int16_t* row = out.ct.hu_i16.data() + out.ct.linear_index(0, j, k);
        const float* src = hu.data() + base + j * step[1] + k * step[2];
        for (int64_t i = 0; i < spec.dims[0]; ++i) {
          const double x = std::clamp(static_cast<double>(src[i * step[0]]), -1024.0, 3071.0);
          row[i] = static_cast<int16_t>(std::lround(x));
        }
      }
    });
  }

  // truth and landmarks in the CT's frame (metres), facts in mm
  out.truth = tree;
  for (auto& b : out.truth.branches) {
    for (auto& p : b.points) {
      p.position_m = (p.position_m + offset) * 1e-3;
      p.radius_m *= 1e-3;
    }
  }
  // the truth holds what the volume shows: a branch ends at its last point inside the grid; one
  // that starts outside it, or past where its parent was cut, is left out with its children
  {
    auto in_grid = [&](const Vector3d& p_m) {
      const Vector3d ijk = out.ct.physical_to_index(p_m * 1000.0);
      for (int a = 0; a < 3; ++a) {
        if (!(ijk[a] >= -1e-6 && ijk[a] <= spec.dims[a] - 1 + 1e-6)) return false;
      }
      return true;
    };
    VesselTree kept;
    std::vector<int> renumber(out.truth.branches.size(), -1);
    for (size_t b = 0; b < out.truth.branches.size(); ++b) {
      VesselBranch br = out.truth.branches[b];
      size_t n = 0;
      while (n < br.points.size() && in_grid(br.points[n].position_m)) ++n;
      const bool parent_ok =
          br.parent < 0 || (renumber[br.parent] >= 0 &&
                            br.parent_point < static_cast<int>(kept.branches[renumber[br.parent]].points.size()));
      if (n < br.points.size()) facts.clipped_branches.push_back(br.name);
      if (n < 2 || !parent_ok) continue;
      br.points.resize(n);
      if (br.parent >= 0) br.parent = renumber[br.parent];
      renumber[b] = static_cast<int>(kept.branches.size());
      kept.branches.push_back(std::move(br));
    }
    out.truth = std::move(kept);
  }
  facts.stenosis_center_mm += offset;
  for (auto& p : facts.plaques) p.center_mm += offset;
  for (auto& p : facts.vein_points_mm) p += offset;
  for (auto& v : facts.crossing_veins) {
    for (auto& p : v.points_mm) p += offset;
  }
  if (facts.laa_gap_mm >= 0) {
    facts.laa_base_mm += offset;
    facts.laa_tip_mm += offset;
  }
  if (!facts.stent_branch.empty()) facts.stent_center_mm += offset;
  out.aortic_seed_mm = aorta[seed_index].position_m + offset;
  auto mark = [&](std::string name, const Vector3d& p_mm) { out.landmarks.push_back({std::move(name), p_mm * 1e-3}); };
  mark("aortic seed", out.aortic_seed_mm);
  mark("aortic root", aorta.front().position_m + offset);
  mark("LM ostium", lm_ostium + offset);
  mark("RCA ostium", rca_ostium + offset);
  mark("stenosis", facts.stenosis_center_mm);
  for (size_t n = 0; n < facts.plaques.size(); ++n) mark("plaque " + std::to_string(n + 1), facts.plaques[n].center_mm);
  if (!facts.vein_points_mm.empty()) {
    mark("vein start", facts.vein_points_mm.front());
    mark("vein end", facts.vein_points_mm.back());
  }
  if (facts.laa_gap_mm >= 0) mark("LA appendage tip", facts.laa_tip_mm);
  for (size_t n = 0; n < facts.crossing_veins.size(); ++n)
    mark("crossing vein " + std::to_string(n + 1),
         facts.crossing_veins[n].points_mm[facts.crossing_veins[n].points_mm.size() / 2]);
  if (!facts.stent_branch.empty()) mark("stent", facts.stent_center_mm);
  mark("LV centre", facts.lv_center_mm);
  mark("heart centre", offset);
  return out;
}

#ifdef PCISIM_HAVE_JSON
namespace {

using ojson = nlohmann::ordered_json;

ojson vec(const Vector3d& v) {
  return ojson::array({v.x(), v.y(), v.z()});
}

ojson mat(const Matrix3d& m) {
  ojson rows = ojson::array();
  for (int r = 0; r < 3; ++r) rows.push_back(ojson::array({m(r, 0), m(r, 1), m(r, 2)}));
  return rows;
}

}  // namespace

void write_phantom_cta(const PhantomCta& cta, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create the folder: " + ec.message());
  write_nrrd(cta.ct, dir + "/ct.nrrd");
  write_vessel_tree_json(cta.truth, dir + "/truth.json");
  write_lesions_json(phantom_cta_lesions(cta), dir + "/truth-lesions.json");

  const PhantomCtaSpec& s = cta.spec;
  const PhantomCtaFacts& f = cta.facts;
  ojson spec = {{"seed", s.seed},
                {"dims", {s.dims[0], s.dims[1], s.dims[2]}},
                {"spacing_mm", vec(s.spacing_mm)},
                {"direction", mat(s.direction)},
                {"noise_sigma_hu", s.noise_sigma_hu},
                {"blur_sigma_mm", s.blur_sigma_mm},
                {"scanner_frame", s.scanner_frame},
                {"stenosis_fraction", s.stenosis_fraction},
                {"with_coronaries", s.with_coronaries},
                {"family", s.family}};
  ojson plaques = ojson::array();
  for (const auto& p : f.plaques) {
    plaques.push_back({{"branch", p.branch},
                       {"arc_length_mm", p.arc_length_mm},
                       {"center_mm", vec(p.center_mm)},
                       {"semi_axes_mm", vec(p.semi_axes_mm)},
                       {"hu", p.hu}});
  }
  ojson tortuosity = ojson::array();
  for (const auto& t : f.tortuosity) {
    tortuosity.push_back({{"branch", t.branch}, {"amplitude_mm", t.amplitude_mm}, {"wavelength_mm", t.wavelength_mm}});
  }
  ojson vein_points = ojson::array();
  for (const auto& p : f.vein_points_mm) vein_points.push_back(vec(p));
  ojson facts = {{"contrast_hu_proximal", f.contrast_hu_proximal},
                 {"fade_hu_per_mm", f.fade_hu_per_mm},
                 {"lumen_floor_hu", f.lumen_floor_hu},
                 {"aorta_hu", f.aorta_hu},
                 {"lv_hu", f.lv_hu},
                 {"la_hu", f.la_hu},
                 {"rv_hu", f.rv_hu},
                 {"ra_hu", f.ra_hu},
                 {"myocardium_hu", f.myocardium_hu},
                 {"fat_sleeve_mm", f.fat_sleeve_mm},
                 {"stenosis",
                  {{"branch", f.stenosis_branch},
                   {"arc_length_mm", f.stenosis_arc_length_mm},
                   {"fraction", f.stenosis_fraction},
                   {"length_mm", f.stenosis_length_mm},
                   {"reference_radius_mm", f.stenosis_reference_radius_mm},
                   {"center_mm", vec(f.stenosis_center_mm)}}},
                 {"plaques", std::move(plaques)},
                 {"vein",
                  {{"beside", f.vein_beside},
                   {"start_mm", f.vein_start_mm},
                   {"length_mm", f.vein_length_mm},
                   {"radius_mm", f.vein_radius_mm},
                   {"hu", f.vein_hu},
                   {"points_mm", std::move(vein_points)}}},
                 {"heart_rotation_deg", vec(f.heart_rotation_deg)},
                 {"heart_rotation", mat(f.heart_rotation)},
                 {"heart_scale", f.heart_scale},
                 {"heart_center_mm", vec(f.heart_center_mm)},
                 {"lv_center_mm", vec(f.lv_center_mm)},
                 {"radius_scale", f.radius_scale},
                 {"dropped_branches", f.dropped_branches},
                 {"clipped_branches", f.clipped_branches},
                 {"tortuosity", std::move(tortuosity)}};
  if (f.family) {
    ojson crossing = ojson::array();
    for (const auto& v : f.crossing_veins) {
      ojson pts = ojson::array();
      for (const auto& p : v.points_mm) pts.push_back(vec(p));
      crossing.push_back({{"crosses", v.crosses},
                          {"radius_mm", v.radius_mm},
                          {"hu", v.hu},
                          {"angle_deg", v.angle_deg},
                          {"points_mm", std::move(pts)}});
    }
    ojson laa = nullptr;
    if (f.laa_gap_mm >= 0) {
      laa = {{"base_mm", vec(f.laa_base_mm)},
             {"tip_mm", vec(f.laa_tip_mm)},
             {"base_radius_mm", f.laa_base_radius_mm},
             {"tip_radius_mm", f.laa_tip_radius_mm},
             {"gap_to_lcx_mm", f.laa_gap_mm}};
    }
    ojson stent = nullptr;
    if (!f.stent_branch.empty()) {
      stent = {{"branch", f.stent_branch},
               {"start_mm", f.stent_start_mm},
               {"length_mm", f.stent_length_mm},
               {"strut_hu", f.stent_strut_hu},
               {"center_mm", vec(f.stent_center_mm)}};
    }
    facts["family"] = {{"heart_axes_scale", vec(f.heart_axes_scale)},
                       {"open_valve", f.open_valve},
                       {"rv_wall_mm", f.rv_wall_mm},
                       {"rv_semi_mm", vec(f.rv_semi_mm)},
                       {"lad_lcx_angle_deg", f.lad_lcx_angle_deg},
                       {"tortuous_branch", f.tortuous_branch},
                       {"side_branches", f.side_branches},
                       {"left_atrial_appendage", std::move(laa)},
                       {"crossing_veins", std::move(crossing)},
                       {"bloom_mm", f.bloom_mm},
                       {"bloom_fraction", f.bloom_fraction},
                       {"stent", std::move(stent)}};
  }
  ojson landmarks = ojson::array();
  for (const auto& l : cta.landmarks) landmarks.push_back({{"name", l.name}, {"position_m", vec(l.position_m)}});
  const ojson doc = {{"format", "pcisim-phantom-cta"},
                     {"version", 1},
                     {"ct", "ct.nrrd"},
                     {"truth", "truth.json"},
                     {"spec", std::move(spec)},
                     {"volume",
                      {{"dims", {cta.ct.dims[0], cta.ct.dims[1], cta.ct.dims[2]}},
                       {"spacing_mm", vec(cta.ct.spacing_mm)},
                       {"origin_mm", vec(cta.ct.origin_mm)},
                       {"direction", mat(cta.ct.direction)}}},
                     {"aortic_seed_mm", vec(cta.aortic_seed_mm)},
                     {"facts", std::move(facts)},
                     {"landmarks", std::move(landmarks)}};
  const std::string path = dir + "/phantom.json";
  std::ofstream file(path);
  if (!file) throw std::runtime_error(path + ": cannot open for writing");
  file << doc.dump(1) << '\n';
  file.flush();
  if (!file) throw std::runtime_error(path + ": write failed");
}
#endif

}  // namespace pcisim::anatomy
