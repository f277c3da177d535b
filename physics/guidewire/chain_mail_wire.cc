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
  // a pre-bent tip resting in a curved catheter lies in the catheter's bend plane, bending the
  // way the catheter curves: that is the tip's orientation at rotation 0
  const Eigen::Vector3d t = path_.exit_direction();
  const Eigen::Vector3d back = path_.point_behind_exit(std::min(0.02, 0.5 * path_.length_m()));
  const Eigen::Vector3d chord = direction(back, path_.exit_m(), t);
  const Eigen::Vector3d curl = (t - chord) - (t - chord).dot(t) * t;
  ref_b_ = curl.norm() > 1e-6 ? Eigen::Vector3d(curl.normalized()) : t.unitOrthogonal();
  nodes_.assign(n_ + 1, Eigen::Vector3d::Zero());
  start_ = nodes_;
  frame_t_.assign(n_, t);
  frame_m_.assign(n_, ref_b_);
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

void ChainMailWire::advance(Frame& f, const Eigen::Vector3d& t_new) const {
  // a torsionally stiff wire: the material frame is the transported one turned by the
  // proximal rotation everywhere (twist is carried to the tip without lag)
  f.b = transport(f.b, f.t, t_new);
  f.b = (f.b - f.b.dot(t_new) * t_new).normalized();  // keep it orthonormal over long chains
  f.t = t_new;
  f.m = std::cos(rotation_) * f.b + std::sin(rotation_) * t_new.cross(f.b);
}

void ChainMailWire::begin_step(double insertion_m, double rotation_rad) {
  start_ = nodes_;  // same size: copies, no allocation
  const double commanded = std::clamp(insertion_m, 0.0, params_.length_m);
  const double push = commanded - commanded_feed_;
  commanded_feed_ = commanded;
  rotation_ = rotation_rad;
  // pulling is always accepted; a push is offered in full, plus up to one link of feed the
  // wire refused before (so a wire blocked for a while does not leap forward at once)
  double feed = commanded;
  if (feed > fed_) feed = std::min(feed, fed_ + std::max(push, 0.0) + rest_m_);
  fed_ = feed;
  const int old_first = first_free_;
  first_free_ = first_free_for(fed_);
  place_kinematic();
  // nodes that just left the catheter start on the straight line out of the exit
  for (int i = first_free_; i < std::min(old_first, n_ + 1); ++i) {
    const double out = fed_ - (n_ - i) * rest_m_;
    nodes_[i] = path_.exit_m() + out * path_.exit_direction();
  }
  forward_sweep(nullptr, 0.0);
}

void ChainMailWire::compute_frames() {
  if (first_free_ > n_) return;
  Frame f = exit_frame();
  for (int j = first_free_ - 1; j < n_; ++j) {
    advance(f, direction(nodes_[j], nodes_[j + 1], f.t));
    frame_t_[j] = f.t;
    frame_m_[j] = f.m;
  }
}

void ChainMailWire::forward_sweep(const LumenQuery* lumen, double eps) {
  // eqs 1-4: the last kinematic node sponsors the first free one, which sponsors the next, ...
  // eqs 2-4 bound each world axis separately; valid_region.cc reads them in the link's frame
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
    Eigen::Vector3d& q = nodes_[j + 1];
    clamp_to_valid_region(nodes_[j], r, q);
    if (lumen) {
      // eq 15 inside the sweep: the wall wins where the region allows, the region always wins
      for (int it = 0; it < 3; ++it) {
        const WallSample s = lumen->sample(q);
        if (s.distance_m <= -eps) break;
        q -= (s.distance_m + eps) * s.normal;
        if (!clamp_to_valid_region(nodes_[j], r, q)) break;
      }
    }
    advance(f, direction(nodes_[j], q, r.axis));
    frame_t_[j] = f.t;
    frame_m_[j] = f.m;
  }
}

void ChainMailWire::bend_pass(bool forward) {
  // eqs 5-10: P* = (Q1 + Q2) / 2 with Q_k = P_k* + delta_k. Read literally, delta is the old
  // relative vector, which keeps any bend forever (a plastic wire). We take delta from the rest
  // shape of the triple (P1, P, P2) fitted rigidly onto the current chord P1-P2 and the
  // material bend plane, so the wire springs back to its rest shape (straight body, pre-bent
  // tip). The centroid is then the chord midpoint moved out of the bend by h sin(theta/2).
  const int ff = first_free_;
  const Frame ex = exit_frame();
  const double h = rest_m_;
  auto target = [&](int i) -> Eigen::Vector3d {
    const Eigen::Vector3d& a = nodes_[i - 1];
    // rest direction of link i-1 seen from link i-2 (the catheter exit when i-2 is held)
    auto from_proximal = [&]() -> Eigen::Vector3d {
      const LinkSpec& l = links_[i - 1];
      const bool held = i - 2 < ff - 1;
      const Eigen::Vector3d& t = held ? ex.t : frame_t_[i - 2];
      const Eigen::Vector3d& m = held ? ex.m : frame_m_[i - 2];
      return a + h * (l.cos_bend * t + l.sin_bend * m);
    };
    if (i == n_) return from_proximal();  // the free tip has one neighbour
    const Eigen::Vector3d& b = nodes_[i + 1];
    const Eigen::Vector3d c = direction(a, b, frame_t_[i - 1]);
    Eigen::Vector3d p = 0.5 * (a + b);
    const LinkSpec& l = links_[i];
    if (l.bend_rad > 0.0) {
      const Eigen::Vector3d& m = frame_m_[i - 1];
      const Eigen::Vector3d m_perp = m - m.dot(c) * c;
      const double len = m_perp.norm();
      if (len > 1e-9) p -= h * std::sin(0.5 * l.bend_rad) * (m_perp / len);
    }
    // the catheter clamps the wire's direction, not only its position
    if (i == ff) p = 0.5 * (p + from_proximal());
    return p;
  };
  if (forward) {
    for (int i = ff; i <= n_; ++i) nodes_[i] = target(i);
  } else {
    for (int i = n_; i >= ff; --i) nodes_[i] = target(i);
  }
}

void ChainMailWire::length_pass() {
  // rest lengths, sponsored from the exit: the push of the hand reaches the tip in one sweep
  for (int j = first_free_ - 1; j < n_; ++j) {
    const Eigen::Vector3d d = direction(nodes_[j], nodes_[j + 1], frame_t_[j]);
    nodes_[j + 1] = nodes_[j] + links_[j].rest_m * d;
  }
}

void ChainMailWire::optimise_pass(int pass_index) {
  if (first_free_ > n_) return;
  compute_frames();
  bend_pass(pass_index % 2 == 0);
  length_pass();
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

void ChainMailWire::restore_limits(const LumenQuery* lumen, double wall_margin_m) {
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
  forward_sweep(lumen, wall_margin_m);
}

void ChainMailWire::end_step() {
  bool finite = std::isfinite(fed_) && std::isfinite(rotation_);
  for (const auto& p : nodes_) finite = finite && p.allFinite();
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
  start_ = nodes_;
}

Eigen::Vector3d ChainMailWire::rest_axis(int j) const {
  Frame f = exit_frame();
  for (int k = first_free_ - 1; k < j - 1 && k < n_; ++k) {
    if (k < 0) continue;
    advance(f, direction(nodes_[k], nodes_[k + 1], f.t));
  }
  const LinkSpec& l = links_[std::clamp(j, 0, n_ - 1)];
  return l.cos_bend * f.t + l.sin_bend * f.m;
}

Eigen::Vector3d ChainMailWire::tip_bend_direction() const {
  // the frame of the last body link: the tip's pre-bend turns towards its director
  int last_body = n_ - 1;
  while (last_body >= 0 && links_[last_body].tip) --last_body;
  Frame f = exit_frame();
  for (int k = std::max(first_free_ - 1, 0); k <= last_body; ++k) {
    advance(f, direction(nodes_[k], nodes_[k + 1], f.t));
  }
  return f.m;
}

}  // namespace pcisim::physics
