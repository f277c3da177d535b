#include "physics/guidewire/chain_mail_wire.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

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

// eq 15 inside the sweep: q moves back inside the wall margin as far as its valid region
// allows; the region always wins. Where projecting along the wall normal leaves the region (a
// joint already at its shear limit against a wall), the region's boundary is searched for the
// point deepest inside the lumen. Returns the wall distance at the final q.
double place_inside(const Eigen::Vector3d& sponsor, const ValidRegion& r, const LumenQuery& lumen, double eps,
                    bool may_swing, Eigen::Vector3d& q) {
  const Eigen::Vector3d q0 = q;
  WallSample s = lumen.sample(q);
  for (int it = 0; it < 3 && s.distance_m > -eps; ++it) {
    q -= (s.distance_m + eps) * s.normal;
    clamp_to_valid_region(sponsor, r, q);
    s = lumen.sample(q);
  }
  if (s.distance_m <= eps) return s.distance_m;
  // blocked ahead: first try shortening the link (compression the catheter may then refuse)
  // rather than swinging it sideways
  const double len = r.length_min_m;
  const Eigen::Vector3d ahead = sponsor + len * direction(sponsor, q0, r.axis);
  const ValidRegion& region = r;
  Eigen::Vector3d shortened = ahead;
  clamp_to_valid_region(sponsor, region, shortened);
  const double d_short = lumen.sample(shortened).distance_m;
  if (d_short <= eps) {
    q = shortened;
    return d_short;
  }
  // rings of directions inside the cone, at the shortest length. Of the candidates reached
  // without crossing a wall (the link's midpoint stays in the lumen) take the one nearest to
  // where q was when any is inside, else the least outside: the deepest point overall may lie
  // in the neighbouring vessel, on the far side of a thin wall near a fork.
  const Eigen::Vector3d u = r.axis.unitOrthogonal(), v = r.axis.cross(u);
  Eigen::Vector3d best = q;
  double best_d = s.distance_m, best_gap = std::numeric_limits<double>::infinity();
  const double max_gap_sq =
      may_swing ? std::numeric_limits<double>::infinity() : 0.25 * r.length_min_m * r.length_min_m;
  bool found_inside = false;
  const int rings = may_swing ? 8 : 4, lengths = may_swing ? 3 : 1;
  for (int li = 0; li < lengths; ++li)
    for (int ring = 0; ring <= rings; ++ring) {
      const double cone = r.beta_rad * ring / rings;
      const double reach = len + (r.length_max_m - len) * li / std::max(lengths - 1, 1);
      for (int k = 0; k < (ring == 0 ? 1 : 16); ++k) {
        const double phi = k * (std::numbers::pi / 8.0);
        const Eigen::Vector3d dir = std::cos(cone) * r.axis + std::sin(cone) * (std::cos(phi) * u + std::sin(phi) * v);
        const Eigen::Vector3d c = sponsor + reach * dir;
        const double d = lumen.sample(c).distance_m;
        const double gap = (c - q0).squaredNorm();
        if (gap > max_gap_sq) continue;  // a swing across the cone flings everything distal
        if (lumen.sample(0.5 * (sponsor + c)).distance_m > 0.0) continue;
        if (d <= eps) {
          if (!found_inside || gap < best_gap) {
            found_inside = true;
            best_gap = gap;
            best_d = d;
            best = c;
          }
        } else if (!found_inside && d < best_d) {
          best_d = d;
          best = c;
        }
      }
    }
  q = best;
  return best_d;
}

// fraction of a pre-bent joint's error corrected per pass: the soft tip yields to the wall and
// never snaps through a thin wall (at a fork) to reach its rest shape on the other side
constexpr double kTipShapeStiffness = 0.3;

}  // namespace

ChainMailWire::ChainMailWire(const GuidewireParams& params, CatheterPath path)
    : params_(params), path_(std::move(path)) {
  links_ = make_link_specs(params_);
  n_ = params_.segment_count;
  for (const LinkSpec& l : links_) tip_links_ += l.tip ? 1 : 0;
  rest_m_ = params_.length_m / n_;
  // a pre-bent tip resting in a curved catheter lies in the catheter's bend plane, bending the
  // way the catheter curves: that is the tip's orientation at rotation 0
  const Eigen::Vector3d t = path_.exit_direction();
  ref_b_ = path_.exit_curl();
  nodes_.assign(n_ + 1, Eigen::Vector3d::Zero());
  start_ = nodes_;
  track_.assign(n_ + 2, Eigen::Vector3d::Zero());
  cum_.assign(n_ + 2, 0.0);
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
  const double fed_before = fed_;
  fed_ = feed;
  advance_along_track(fed_ - fed_before);
  forward_sweep(nullptr, 0.0, false);
}

void ChainMailWire::advance_along_track(double delta_m) {
  // pushing translates the wire along itself (paper: the sponsor translates along the wire's
  // direction and its neighbours follow): every free node moves delta along the polyline the
  // wire occupied, from the catheter exit through the free nodes and on along the tip's
  // direction. The body slides like a train on its own rails; only the tip breaks new ground.
  // A tip that touches nothing does not lead: in free space the body slides along its own
  // line and carries the tip with it (a free wire stays straight behind its shaped tip).
  const int old_first = first_free_;
  const int last_body = n_ - tip_links_;  // node where the shaped tip begins
  const int end_node = tip_touching_ ? n_ : last_body;
  track_[0] = path_.exit_m();
  cum_[0] = 0.0;
  int count = 1;
  for (int i = old_first; i <= end_node; ++i, ++count) {
    track_[count] = start_[i];
    cum_[count] = cum_[count - 1] + (track_[count] - track_[count - 1]).norm();
  }
  Eigen::Vector3d ahead = path_.exit_direction();
  if (count >= 3) {
    ahead = direction(track_[count - 2], track_[count - 1], ahead);
  } else if (count == 2) {
    ahead = direction(track_[0], track_[1], ahead);
  }
  first_free_ = first_free_for(fed_);
  place_kinematic();
  int seg = 1;  // track segment [seg-1, seg] holding the last query; queries only increase
  auto on_track = [&](double sigma) -> Eigen::Vector3d {
    if (sigma <= 0.0) return path_.point_behind_exit(-sigma);
    if (sigma >= cum_[count - 1]) return track_[count - 1] + (sigma - cum_[count - 1]) * ahead;
    while (seg < count - 1 && cum_[seg] < sigma) ++seg;
    while (seg > 1 && cum_[seg - 1] > sigma) --seg;
    const double len = cum_[seg] - cum_[seg - 1];
    const double f = len > 0.0 ? (sigma - cum_[seg - 1]) / len : 0.0;
    return track_[seg - 1] + f * (track_[seg] - track_[seg - 1]);
  };
  for (int i = first_free_; i <= end_node; ++i) {
    nodes_[i] = on_track(i >= old_first ? cum_[i - old_first + 1] + delta_m : fed_ - (n_ - i) * rest_m_);
  }
  if (end_node < n_) {
    // the free tip rides on the end of the body
    const Eigen::Vector3d carry = nodes_[last_body] - start_[last_body];
    for (int i = std::max(end_node + 1, first_free_); i <= n_; ++i) {
      nodes_[i] = i >= old_first ? Eigen::Vector3d(start_[i] + carry) : on_track(fed_ - (n_ - i) * rest_m_);
    }
  }
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

double ChainMailWire::forward_sweep(const LumenQuery* lumen, double eps, bool may_swing) {
  // eqs 1-4: the last kinematic node sponsors the first free one, which sponsors the next, ...
  // eqs 2-4 bound each world axis separately; valid_region.cc reads them in the link's frame
  double worst = -1.0;
  if (lumen) tip_touching_ = false;
  if (first_free_ > n_) return worst;
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
      const double d = place_inside(nodes_[j], r, *lumen, eps, may_swing, q);
      worst = std::max(worst, d);
      // within a margin's width of the wall counts as touching
      if (l.tip && d > -2.0 * eps - 1e-6) tip_touching_ = true;
    }
    advance(f, direction(nodes_[j], q, r.axis));
    frame_t_[j] = f.t;
    frame_m_[j] = f.m;
  }
  return worst;
}

void ChainMailWire::backward_contact_sweep(const LumenQuery& lumen, double eps) {
  // the tip sponsors the sweep back to the exit (chain-mail works from either end): a tip
  // jammed head-on into the wall turns the joints behind it instead of staying outside
  Eigen::Vector3d& tip = nodes_[n_];
  const WallSample s = lumen.sample(tip);
  if (s.distance_m > -eps) tip -= (s.distance_m + eps) * s.normal;
  for (int j = n_ - 1; j >= first_free_; --j) {
    const LinkSpec& l = links_[j];
    ValidRegion r;
    if (j + 1 < n_) {
      // rest direction of link j seen from link j+1: undo link j+1's pre-bend
      const LinkSpec& ln = links_[j + 1];
      const Eigen::Vector3d t = direction(nodes_[j + 1], nodes_[j + 2], frame_t_[j + 1]);
      Eigen::Vector3d m = frame_m_[j + 1] - frame_m_[j + 1].dot(t) * t;
      m = m.norm() > 1e-9 ? Eigen::Vector3d(m.normalized()) : t.unitOrthogonal();
      r.axis = -(ln.cos_bend * t - ln.sin_bend * m);
      r.beta_rad = ln.beta_rad;
      r.cos_beta = ln.cos_beta;
    } else {
      r.axis = direction(nodes_[j + 1], nodes_[j], -frame_t_[j]);
      r.beta_rad = std::numbers::pi;
      r.cos_beta = -1.0;
    }
    r.length_min_m = l.length_min_m;
    r.length_max_m = l.length_max_m;
    // a neighbour already valid and inside stops the propagation (chain-mail, fig. 3)
    const bool moved = clamp_to_valid_region(nodes_[j + 1], r, nodes_[j]);
    const double d = lumen.sample(nodes_[j]).distance_m;
    if (!moved && d <= eps) break;
    place_inside(nodes_[j + 1], r, lumen, eps, false, nodes_[j]);
  }
}

void ChainMailWire::bend_pass(bool forward) {
  // eqs 5-10 per triple (P1, P, P2): Q_k = P_k* + delta_k and E = sum |P* - Q_k|^2. Read
  // literally, delta is the old relative vector, which keeps any bend forever (a plastic wire);
  // we take delta from the rest shape of the triple fitted rigidly onto the current chord P1-P2
  // and the material bend plane, so the wire springs back to its rest shape (straight body,
  // pre-bent tip). The centroid of eq 10 is then the chord midpoint moved out of the bend by
  // h sin(theta/2). Eq 10 moves P alone, which leaves a free end undetermined (a family of
  // kinked equilibria); we minimise the same energy over all three nodes, weighted by which
  // may move (catheter-held nodes do not), which is eq 10 when both neighbours are held.
  const int ff = first_free_;
  const Frame ex = exit_frame();
  const double h = rest_m_;
  auto project = [&](int i) {
    // triple centred on node i: nodes i-1, i, i+1; the bend of link i relative to link i-1.
    // A pre-bent joint moves only its distal node: moving all three would make the rest bend
    // push the body sideways (the bend's direction comes from the exit's frame, so it is not
    // a balanced internal force) and that spurious curvature decays over thousands of passes.
    const LinkSpec& l = links_[i];
    const bool shaped = l.bend_rad > 0.0;
    const double wa = (i - 1 >= ff && !shaped) ? 1.0 : 0.0, wp = (i >= ff && !shaped) ? 1.0 : 0.0, wb = 1.0;
    Eigen::Vector3d& a = nodes_[i - 1];
    Eigen::Vector3d& p = nodes_[i];
    Eigen::Vector3d& b = nodes_[i + 1];
    const bool held = i - 1 < ff - 1;  // link i-1 lies in the catheter
    const Eigen::Vector3d& t_prev = held ? ex.t : frame_t_[i - 1];
    const Eigen::Vector3d& m_prev = held ? ex.m : frame_m_[i - 1];
    const Eigen::Vector3d c = direction(a, b, t_prev);
    Eigen::Vector3d goal = 0.5 * (a + b);
    if (shaped) {
      const Eigen::Vector3d m_perp = m_prev - m_prev.dot(c) * c;
      const double len = m_perp.norm();
      if (len > 1e-9) goal -= h * std::sin(0.5 * l.bend_rad) * (m_perp / len);
    }
    // C = goal - P is linear in (a, p, b) with weights (1/2, -1, 1/2): project it
    const Eigen::Vector3d cv = goal - p;
    const double denom = 0.25 * wa + wp + 0.25 * wb;
    const Eigen::Vector3d lambda = (shaped ? kTipShapeStiffness : 1.0) * cv / denom;
    a -= 0.5 * wa * lambda;
    p += wp * lambda;
    b -= 0.5 * wb * lambda;
  };
  const int lo = std::max(ff - 1, 1), hi = n_ - 1;
  if (forward) {
    for (int i = lo; i <= hi; ++i) project(i);
  } else {
    for (int i = hi; i >= lo; --i) project(i);
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
  length_pass();
  bend_pass(pass_index % 2 == 0);
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
  // what a forward sweep leaves outside is worked back from the tip, then swept forward again
  const double worst = forward_sweep(lumen, wall_margin_m, true);
  if (lumen && worst > wall_margin_m) {
    backward_contact_sweep(*lumen, wall_margin_m);
    forward_sweep(lumen, wall_margin_m, true);
  }
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
  for (int k = first_free_ - 1; k < j && k < n_; ++k) {
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
