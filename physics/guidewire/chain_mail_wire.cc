#include "physics/guidewire/chain_mail_wire.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "physics/guidewire/valid_region.h"

namespace pcisim::physics {
namespace {

// rotates v by the smallest rotation taking unit a onto unit c (parallel transport)
Eigen::Vector3d transport(const Eigen::Vector3d& v, const Eigen::Vector3d& a, const Eigen::Vector3d& c) {
  const Eigen::Vector3d k = a.cross(c);
  const double cos_t = a.dot(c);
  if (cos_t < -0.999999) {
    // reversed tangent: keep v's part across c
    const Eigen::Vector3d w = v - v.dot(c) * c;
    const double n = w.norm();
    return n > 1e-12 ? Eigen::Vector3d(w / n) : c.unitOrthogonal();
  }
  return v * cos_t + k.cross(v) + k * (k.dot(v) / (1.0 + cos_t));
}

// unit direction from a to b, or `fallback` when they coincide
Eigen::Vector3d direction(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& fallback) {
  const Eigen::Vector3d d = b - a;
  const double n = d.norm();
  return n > 1e-12 ? Eigen::Vector3d(d / n) : fallback;
}

}  // namespace

ChainMailWire::ChainMailWire(const GuidewireParams& params, CatheterPath path)
    : params_(params), path_(std::move(path)) {
  links_ = make_link_specs(params_);
  n_ = params_.segment_count;
  rest_m_ = params_.length_m / n_;
  ref_b_ = path_.exit_direction().unitOrthogonal();
  nodes_.assign(n_ + 1, Eigen::Vector3d::Zero());
  start_ = nodes_;
  twist_.assign(n_, 0.0);
  hold_.assign(n_, 0);
  frame_t_.assign(n_, Eigen::Vector3d::UnitZ());
  frame_m_.assign(n_, Eigen::Vector3d::UnitX());
  first_free_ = n_ + 1;
  place_kinematic();
  start_ = nodes_;
}

int ChainMailWire::first_free_for(double fed_m) const {
  // node i is out once fed - (N - i) h > 0
  const int i = static_cast<int>(std::floor(n_ - fed_m / rest_m_ + 1e-9)) + 1;
  return std::clamp(i, 1, n_ + 1);
}

void ChainMailWire::place_kinematic() {
  for (int i = 0; i < first_free_ && i <= n_; ++i) {
    nodes_[i] = path_.point_behind_exit((n_ - i) * rest_m_ - fed_);
  }
}

ChainMailWire::Frame ChainMailWire::exit_frame() const {
  // the wire inside the catheter turns rigidly with the instrument
  Frame f;
  f.t = path_.exit_direction();
  f.b = ref_b_;
  f.m = std::cos(rotation_) * f.b + std::sin(rotation_) * f.t.cross(f.b);
  return f;
}

void ChainMailWire::advance(Frame& f, const Eigen::Vector3d& t_new, double twist) const {
  f.b = transport(f.b, f.t, t_new);
  f.b = (f.b - f.b.dot(t_new) * t_new).normalized();  // keep it orthonormal over long chains
  f.t = t_new;
  f.m = std::cos(twist) * f.b + std::sin(twist) * t_new.cross(f.b);
}

void ChainMailWire::begin_step(double insertion_m, double rotation_rad) {
  start_ = nodes_;  // same size: copies, no allocation
  commanded_feed_ = std::clamp(insertion_m, 0.0, params_.length_m);
  rotation_ = rotation_rad;
  const int old_first = first_free_;
  // try to feed all that is asked; what the vessel refuses comes back in restore_limits()
  fed_ = commanded_feed_;
  first_free_ = first_free_for(fed_);
  place_kinematic();
  // nodes that just left the catheter start on the straight line out of the exit
  for (int i = first_free_; i < std::min(old_first, n_ + 1); ++i) {
    const double out = fed_ - (n_ - i) * rest_m_;
    nodes_[i] = path_.exit_m() + out * path_.exit_direction();
  }
  sweep_twist();
  forward_sweep();
}

void ChainMailWire::sweep_twist() {
  // chain-mail on angles: the catheter turns rigidly; a free link follows its proximal
  // neighbour only when their difference passes the twist limit (torque transmission)
  const int j0 = std::max(first_free_ - 1, 0);
  for (int j = 0; j < j0; ++j) twist_[j] = rotation_;
  double prev = rotation_;
  for (int j = j0; j < n_; ++j) {
    const double lim = links_[j].twist_limit_rad;
    twist_[j] = std::clamp(twist_[j], prev - lim, prev + lim);
    prev = twist_[j];
  }
}

void ChainMailWire::relax_twist() {
  // physical optimisation of the angles (eqs 7-10 read for twist): between held links the twist
  // spreads evenly; past the last held link the free end carries no torque and turns with it
  const int j0 = std::max(first_free_ - 1, 0);
  int prev_j = j0 - 1;
  double prev = rotation_;
  for (int j = j0; j < n_; ++j) {
    if (!hold_[j]) continue;
    const int gap = j - prev_j;
    for (int k = prev_j + 1; k < j; ++k) twist_[k] = prev + (twist_[j] - prev) * (k - prev_j) / gap;
    prev_j = j;
    prev = twist_[j];
  }
  for (int k = prev_j + 1; k < n_; ++k) twist_[k] = prev;
}

void ChainMailWire::forward_sweep() {
  // eqs 1-4: the last kinematic node sponsors the first free one, which sponsors the next, ...
  if (first_free_ > n_) return;
  Frame f = exit_frame();
  for (int j = first_free_ - 1; j < n_; ++j) {
    const LinkSpec& l = links_[j];
    ValidRegion r;
    r.axis = l.cos_bend * f.t + l.sin_bend * f.m;
    r.length_min_m = l.length_min_m;
    r.length_max_m = l.length_max_m;
    r.beta_rad = l.beta_rad;
    r.cos_beta = l.cos_beta;
    clamp_to_valid_region(nodes_[j], r, nodes_[j + 1]);
    advance(f, direction(nodes_[j], nodes_[j + 1], r.axis), twist_[j]);
  }
}

void ChainMailWire::backward_sweep_compression() {
  // the distal node sponsors its proximal neighbour, for compression only: a wire pushed
  // against the wall shortens back towards the catheter instead of into the wall
  for (int i = n_ - 1; i >= first_free_; --i) {
    const LinkSpec& l = links_[i];
    const Eigen::Vector3d d = nodes_[i] - nodes_[i + 1];
    const double len = d.norm();
    if (len >= l.length_min_m) continue;
    const Eigen::Vector3d dir = len > 1e-12 ? Eigen::Vector3d(d / len) : Eigen::Vector3d(-path_.exit_direction());
    nodes_[i] = nodes_[i + 1] + l.length_min_m * dir;
  }
}

void ChainMailWire::restore_limits() {
  if (first_free_ <= n_) {
    backward_sweep_compression();
    // the catheter node behind the first free one may only slide back along the exit line:
    // the slide s with |w + s e| = length_min is feed the wire refuses
    const int i = first_free_;
    const LinkSpec& l = links_[i - 1];
    const Eigen::Vector3d w = nodes_[i] - nodes_[i - 1];
    if (w.norm() < l.length_min_m) {
      const double we = w.dot(path_.exit_direction());
      const double disc = we * we - w.squaredNorm() + l.length_min_m * l.length_min_m;
      const double slide = -we + std::sqrt(std::max(disc, 0.0));
      if (slide > 0.0) {
        fed_ = std::max(fed_ - slide, 0.0);
        first_free_ = first_free_for(fed_);
        place_kinematic();
      }
    }
  }
  forward_sweep();
}

void ChainMailWire::compute_frames() {
  if (first_free_ > n_) return;
  Frame f = exit_frame();
  for (int j = first_free_ - 1; j < n_; ++j) {
    advance(f, direction(nodes_[j], nodes_[j + 1], f.t), twist_[j]);
    frame_t_[j] = f.t;
    frame_m_[j] = f.m;
  }
}

void ChainMailWire::optimise_pass(int pass_index) {
  relax_twist();
  if (first_free_ > n_) return;
  compute_frames();
  const Frame ex = exit_frame();
  const int j0 = first_free_ - 1;  // first link with a free end
  // eqs 5-10: P* = (Q1 + Q2) / 2 with Q_k = P_k* + delta_k. Read literally, delta is the old
  // relative vector, which keeps any bend forever (a plastic wire); we carry the rest relative
  // vector in the neighbour's current material frame, so the wire springs back to its rest
  // shape (straight body, pre-bent tip).
  auto target = [&](int i) -> Eigen::Vector3d {
    const int jp = i - 1;  // link from the proximal neighbour
    const Eigen::Vector3d& tp = jp - 1 >= j0 ? frame_t_[jp - 1] : ex.t;
    const Eigen::Vector3d& mp = jp - 1 >= j0 ? frame_m_[jp - 1] : ex.m;
    const LinkSpec& lp = links_[jp];
    const Eigen::Vector3d q1 = nodes_[i - 1] + lp.rest_m * (lp.cos_bend * tp + lp.sin_bend * mp);
    if (i == n_) return q1;  // the free tip has one neighbour
    Eigen::Vector3d back;
    if (i + 1 < n_) {
      // rest direction of link i predicted from link i+1 (inverse of the pre-bend rotation)
      const LinkSpec& ln = links_[i + 1];
      back = ln.cos_bend * frame_t_[i + 1] - ln.sin_bend * frame_m_[i + 1];
    } else {
      back = frame_t_[i];  // the last link: only its length is restored
    }
    const Eigen::Vector3d q2 = nodes_[i + 1] - links_[i].rest_m * back;
    return 0.5 * (q1 + q2);
  };
  if (pass_index % 2 == 0) {
    for (int i = first_free_; i <= n_; ++i) nodes_[i] = target(i);
  } else {
    for (int i = n_; i >= first_free_; --i) nodes_[i] = target(i);
  }
}

void ChainMailWire::end_step() {
  bool finite = std::isfinite(fed_) && std::isfinite(rotation_);
  for (const auto& p : nodes_) finite = finite && p.allFinite();
  for (double t : twist_) finite = finite && std::isfinite(t);
  if (finite) return;
  // should never happen; if it does, start again from a straight wire rather than spread NaN
  ++recoveries_;
  if (!std::isfinite(fed_)) fed_ = 0.0;
  if (!std::isfinite(rotation_)) rotation_ = 0.0;
  first_free_ = first_free_for(fed_);
  place_kinematic();
  for (int i = first_free_; i <= n_; ++i) {
    nodes_[i] = path_.exit_m() + (fed_ - (n_ - i) * rest_m_) * path_.exit_direction();
  }
  std::fill(twist_.begin(), twist_.end(), rotation_);
  std::fill(hold_.begin(), hold_.end(), 0);
  start_ = nodes_;
}

Eigen::Vector3d ChainMailWire::tip_bend_direction() const {
  Frame f = exit_frame();
  const int j0 = std::max(first_free_ - 1, 0);
  for (int j = j0; j < n_; ++j) advance(f, direction(nodes_[j], nodes_[j + 1], f.t), twist_[j]);
  return f.m;
}

}  // namespace pcisim::physics
