#include "physics/blood/blood_chain_mail.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "physics/param_checks.h"

namespace pcisim::physics {
namespace {

constexpr int kRing = 6;               // chain-mails around the axis at each station
constexpr double kRingFraction = 0.6;  // of the radius: samples the profile between axis and wall
constexpr int kHashBits = 14;
constexpr uint32_t kHashMask = (1u << kHashBits) - 1;

uint32_t hash_cell(int x, int y, int z) {
  return (static_cast<uint32_t>(x) * 73856093u ^ static_cast<uint32_t>(y) * 19349663u ^
          static_cast<uint32_t>(z) * 83492791u) &
         kHashMask;
}

Eigen::Vector3i cell_of(const Eigen::Vector3d& p, double h) {
  return (p / h).array().floor().cast<int>();
}

}  // namespace

double coronary_flow_fraction(double phase, double pulsatility) {
  // left coronary flow is throttled while the myocardium contracts and peaks early in diastole
  // (diastolic-to-systolic mean velocity ratio ~2 by Doppler wire in the LAD); here systole
  // carries 1 - p and diastole a sin^2 hump scaled so the cycle mean is exactly 1
  const double p = std::clamp(pulsatility, 0.0, 1.0);
  const double f = phase - std::floor(phase);
  if (f < kSystoleFraction) return 1.0 - p;
  const double d = 1.0 - kSystoleFraction;
  const double hump = std::sin(std::numbers::pi * (f - kSystoleFraction) / d);
  return 1.0 - p + p * (2.0 / d) * hump * hump;
}

void validate(const BloodFlowParams& b) {
  require(kBloodMeanVelocityMPerS.contains(b.mean_velocity_m_per_s),
          "blood_flow.mean_velocity_m_per_s: expected " + kBloodMeanVelocityMPerS.describe());
  require(kBloodDriftGain.contains(b.drift_gain), "blood_flow.drift_gain: expected " + kBloodDriftGain.describe());
  require(kBloodPulsatility.contains(b.pulsatility),
          "blood_flow.pulsatility: expected " + kBloodPulsatility.describe());
  require(kBloodCellSpacingM.contains(b.cell_spacing_m),
          "blood_flow.cell_spacing_m: expected " + kBloodCellSpacingM.describe());
  require(kBloodLinkRadiusM.contains(b.link_radius_m),
          "blood_flow.link_radius_m: expected " + kBloodLinkRadiusM.describe());
}

BloodChainMail::BloodChainMail(const BloodFlowParams& params, const anatomy::VesselTree& tree) : params_(params) {
  validate(params);
  const int aorta = tree.find("aorta");
  for (int b = 0; b < static_cast<int>(tree.branches.size()); ++b) {
    const auto& pts = tree.branches[b].points;
    if (b == aorta || pts.size() < 2) continue;  // the wire crosses the aorta inside its catheter
    Branch br;
    br.first_point = static_cast<int>(point_m_.size());
    br.point_count = static_cast<int>(pts.size());
    double s = 0.0;
    Eigen::Vector3d n_prev = Eigen::Vector3d::Zero();
    for (int i = 0; i < br.point_count; ++i) {
      if (i > 0) s += (pts[i].position_m - pts[i - 1].position_m).norm();
      const Eigen::Vector3d t =
          (pts[std::min(i + 1, br.point_count - 1)].position_m - pts[std::max(i - 1, 0)].position_m).normalized();
      // a normal carried along the branch without twisting (parallel transport)
      Eigen::Vector3d n = i == 0 ? t.unitOrthogonal() : Eigen::Vector3d(n_prev - n_prev.dot(t) * t);
      if (n.norm() < 1e-9) n = t.unitOrthogonal();
      n.normalize();
      n_prev = n;
      point_m_.push_back(pts[i].position_m);
      tangent_.push_back(t);
      normal_.push_back(n);
      radius_m_.push_back(pts[i].radius_m);
      arc_m_.push_back(s);
    }
    br.length_m = s;
    const int branch_index = static_cast<int>(branches_.size());
    branches_.push_back(br);
    for (double c = 0.5 * params_.cell_spacing_m; c < s; c += params_.cell_spacing_m) {
      cells_.push_back({branch_index, c, 0.0, 0.0});
      for (int k = 0; k < kRing; ++k) {
        cells_.push_back({branch_index, c, 2.0 * std::numbers::pi * k / kRing, kRingFraction});
      }
    }
  }
  pos_.resize(cells_.size());
  vel_.resize(cells_.size());
  cell_bucket_.resize(cells_.size());
  bucket_cells_.resize(cells_.size());
  bucket_start_.assign((1u << kHashBits) + 1, 0);
  bucket_fill_.assign(1u << kHashBits, 0);
  for (int c = 0; c < cell_count(); ++c) place(c);
  rebuild_hash();
}

void BloodChainMail::place(int c) {
  const Cell& cell = cells_[c];
  const Branch& br = branches_[cell.branch];
  const auto first = arc_m_.begin() + br.first_point;
  const auto last = first + br.point_count;
  // the centerline segment holding s
  int k = static_cast<int>(std::upper_bound(first, last, cell.s_m) - first) - 1;
  k = std::clamp(k, 0, br.point_count - 2);
  const int i = br.first_point + k;
  const double len = arc_m_[i + 1] - arc_m_[i];
  const double u = len > 0.0 ? std::clamp((cell.s_m - arc_m_[i]) / len, 0.0, 1.0) : 0.0;
  const Eigen::Vector3d axis = (1.0 - u) * point_m_[i] + u * point_m_[i + 1];
  const Eigen::Vector3d t = ((1.0 - u) * tangent_[i] + u * tangent_[i + 1]).normalized();
  const Eigen::Vector3d n = (normal_[i] - normal_[i].dot(t) * t).normalized();
  const Eigen::Vector3d b = t.cross(n);
  const double r = (1.0 - u) * radius_m_[i] + u * radius_m_[i + 1];
  const double rf = cell.radial_fraction;
  pos_[c] = axis + rf * r * (std::cos(cell.ring_angle) * n + std::sin(cell.ring_angle) * b);
  vel_[c] = speed_m_per_s(cell) * t;
}

double BloodChainMail::speed_m_per_s(const Cell& cell) const {
  // Poiseuille: 2 x the mean on the axis, 0 at the wall
  const double rf = cell.radial_fraction;
  return params_.mean_velocity_m_per_s * flow_fraction_ * 2.0 * (1.0 - rf * rf);
}

void BloodChainMail::step(double dt_s, double phase) {
  flow_fraction_ = coronary_flow_fraction(phase, params_.pulsatility);
  for (int c = 0; c < cell_count(); ++c) {
    Cell& cell = cells_[c];
    const double length = branches_[cell.branch].length_m;
    // on along the branch, then round to its start (the same blood keeps circulating, so
    // nothing is allocated)
    cell.s_m += speed_m_per_s(cell) * dt_s;
    if (length > 0.0 && cell.s_m >= length) cell.s_m = std::fmod(cell.s_m, length);
    place(c);
  }
  rebuild_hash();
}

void BloodChainMail::rebuild_hash() {
  // counting sort of the cells into buckets of link-radius cells
  std::fill(bucket_start_.begin(), bucket_start_.end(), 0);
  const double h = params_.link_radius_m;
  for (int c = 0; c < cell_count(); ++c) {
    const Eigen::Vector3i g = cell_of(pos_[c], h);
    cell_bucket_[c] = static_cast<int>(hash_cell(g.x(), g.y(), g.z()));
    ++bucket_start_[cell_bucket_[c] + 1];
  }
  for (size_t b = 1; b < bucket_start_.size(); ++b) bucket_start_[b] += bucket_start_[b - 1];
  std::copy(bucket_start_.begin(), bucket_start_.end() - 1, bucket_fill_.begin());
  for (int c = 0; c < cell_count(); ++c) bucket_cells_[bucket_fill_[cell_bucket_[c]]++] = c;
}

Eigen::Vector3d BloodChainMail::linked_velocity(const Eigen::Vector3d& p) const {
  if (cells_.empty() || !p.allFinite()) return Eigen::Vector3d::Zero();
  const double h = params_.link_radius_m;
  const Eigen::Vector3i g = cell_of(p, h);
  uint32_t buckets[27];
  int bucket_n = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const uint32_t b = hash_cell(g.x() + dx, g.y() + dy, g.z() + dz);
        if (std::find(buckets, buckets + bucket_n, b) == buckets + bucket_n)
          buckets[bucket_n++] = b;  // two cells, one bucket
      }
  // the node links to the blood of one vessel, the one whose chain-mail is nearest: at a fork
  // the flows of parent and daughters would otherwise average into a direction none of them has
  int branch = -1;
  double nearest = h;
  for (int k = 0; k < bucket_n; ++k)
    for (int j = bucket_start_[buckets[k]]; j < bucket_start_[buckets[k] + 1]; ++j) {
      const int c = bucket_cells_[j];
      const double d = (pos_[c] - p).norm();
      if (d <= nearest) {
        nearest = d;
        branch = cells_[c].branch;
      }
    }
  if (branch < 0) return Eigen::Vector3d::Zero();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double wsum = 0.0;
  for (int k = 0; k < bucket_n; ++k)
    for (int j = bucket_start_[buckets[k]]; j < bucket_start_[buckets[k] + 1]; ++j) {
      const int c = bucket_cells_[j];
      if (cells_[c].branch != branch) continue;
      const double d = (pos_[c] - p).norm();
      if (d > h) continue;
      // eq 12's text: weights inversely proportional to distance (its printed w_i = d_i / sum d
      // would grow with distance, the opposite); softened by a quarter spacing so a chain-mail
      // passing right by a node does not jerk it
      const double w = 1.0 / (d + 0.25 * params_.cell_spacing_m);
      sum += w * vel_[c];
      wsum += w;
    }
  return wsum > 0.0 ? Eigen::Vector3d(sum / wsum) : Eigen::Vector3d::Zero();
}

void BloodChainMail::apply(ChainMailWire& wire, double dt_s) const {
  apply(wire.mutable_nodes_m(), wire.first_free_node(), dt_s);
}

void BloodChainMail::apply(std::span<Eigen::Vector3d> nodes, int first_free, double dt_s) const {
  const double gain = params_.drift_gain * dt_s;
  for (int i = first_free; i < static_cast<int>(nodes.size()); ++i) nodes[i] += gain * linked_velocity(nodes[i]);
}

}  // namespace pcisim::physics
