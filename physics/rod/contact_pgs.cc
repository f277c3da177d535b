#include "physics/rod/contact_pgs.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>

namespace pcisim::physics::rod {
namespace {

// the subspace step's solves, at most: each after the first lets go of the push that would have
// turned into a pull
constexpr int kSubspaceRounds = 8;

// under-relaxation of cycling sweeps: judged every kRelaxationWindow sweeps, halved down to
// kLeastRelaxation
constexpr int kRelaxationWindow = 8;
constexpr double kLeastRelaxation = 0.25;

// two unit vectors spanning the plane normal to n
void tangent_basis(const Eigen::Vector3d& n, Eigen::Vector3d* t1, Eigen::Vector3d* t2) {
  const Eigen::Vector3d helper = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  *t1 = n.cross(helper).normalized();
  *t2 = n.cross(*t1);
}

// sliding: the tangent impulse of magnitude c against the slip it leaves. With the slip
// s = s_o + W_tt L_t (s_o: the slip without this contact's friction), L_t = -c s / |s| says that
// s minimises the strictly convex  1/2 (s - s_o)' M (s - s_o) + c |s|,  M = W_tt^-1 (its
// gradient is M (s - s_o) + c s / |s| = -L_t + c s / |s|). Projecting the stick impulse on the
// cone instead would put friction along W_tt^-1 s, not against s, where W_tt is anisotropic (a
// rod is far stiffer along its axis than across it). Newton on s, halving a step that does not
// descend; the caller has made sure s = 0 is not the answer (|M s_o| > c).
Eigen::Vector2d slide_on_cone(const Eigen::Matrix2d& m, const Eigen::Vector2d& s_o, double c) {
  auto objective = [&](const Eigen::Vector2d& s) { return 0.5 * (s - s_o).dot(m * (s - s_o)) + c * s.norm(); };
  Eigen::Vector2d s = s_o;
  double f = objective(s);
  const double scale = s_o.norm();
  for (int it = 0; it < 30 && s.norm() > 0.0; ++it) {
    const double len = s.norm();
    const Eigen::Vector2d u = s / len;
    const Eigen::Vector2d g = m * (s - s_o) + c * u;
    const Eigen::Matrix2d hess = m + (c / len) * (Eigen::Matrix2d::Identity() - u * u.transpose());
    const Eigen::Vector2d step = -hess.inverse() * g;
    double a = 1.0;
    Eigen::Vector2d next = s + step;
    double f_next = objective(next);
    while (f_next > f && a > 1e-8) {
      a *= 0.5;
      next = s + a * step;
      f_next = objective(next);
    }
    if (!(f_next <= f)) break;
    s = next;
    f = f_next;
    if ((a * step).norm() <= 1e-14 * scale) break;
  }
  if (!(s.norm() > 0.0)) return Eigen::Vector2d::Zero();
  return -c * s.normalized();
}

// A frictionless contact on a curved wall: its push L and its curved wall's impulse c (in the
// tangent basis t) found together, the rest of the problem held. With m0 the node's motion
// without its own impulses, e = t'(m0 - d_0), S = t' S t and the blocks of W_aa in (n, t):
//   c(L) = -(I + L S w_tt)^-1 L S (e - L w_tn)       (the curved-wall law, C = -L S (d_t - d_0))
//   phi(L) = gap + n'm0 - L w_nn + w_nt c(L) = 0     (the gap closed), L >= 0
// Newton on L inside a bracket that halves where a step would leave it. Solved one after the
// other, the push and c can alternate without settling where the wall turns fast (a tip in a
// rounded end: L S w_tt reaches thousands), as one end-on column's single contact did for 100
// sweeps (issue #33, session 32). Returns L and sets *c.
double push_on_curved_wall(double phi0, double w_nn, const Eigen::Vector2d& w_nt, const Eigen::Vector2d& w_tn,
                           const Eigen::Matrix2d& w_tt, const Eigen::Matrix2d& s, const Eigen::Vector2d& e,
                           Eigen::Vector2d* c) {
  c->setZero();
  if (!(phi0 > 0.0) || !(w_nn > 0.0) || !std::isfinite(phi0)) return 0.0;  // apart, or nothing to push
  // phi and its slope at l (c and dc/dl from differentiating A c = -l S (e - l w_tn), A = I + l S w_tt)
  auto eval = [&](double l, Eigen::Vector2d* c_out, double* slope) {
    const Eigen::Matrix2d a = Eigen::Matrix2d::Identity() + l * s * w_tt;
    const Eigen::Matrix2d a_inv = a.inverse();
    const Eigen::Vector2d r = e - l * w_tn;
    *c_out = -a_inv * (l * (s * r));
    const Eigen::Vector2d dc = a_inv * (-(s * r) + l * (s * w_tn) - s * (w_tt * *c_out));
    *slope = -w_nn + w_nt.dot(dc);
    return phi0 - l * w_nn + w_nt.dot(*c_out);
  };
  double lo = 0.0, hi = phi0 / w_nn;
  Eigen::Vector2d c_hi;
  double slope = 0.0;
  // an upper end where the gap is closed
  for (int k = 0; k < 60 && eval(hi, &c_hi, &slope) > 0.0; ++k) {
    lo = hi;
    hi *= 2.0;
  }
  if (!std::isfinite(hi)) return 0.0;
  double l = hi;
  for (int it = 0; it < 60; ++it) {
    const double phi = eval(l, c, &slope);
    if (phi > 0.0)
      lo = l;
    else
      hi = l;
    if (std::abs(phi) <= 1e-15 * phi0 || hi - lo <= 1e-15 * hi) return l;
    double next = slope < 0.0 ? l - phi / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    l = next;
  }
  eval(l, c, &slope);  // (*c at the push returned)
  return l;
}

}  // namespace

ContactPgs::ContactPgs(int max_contacts) {
  if (max_contacts < 0) throw std::invalid_argument("contact solve: max_contacts must be >= 0");
  motion_.assign(max_contacts, Eigen::Vector3d::Zero());
  curvature_.assign(max_contacts, Eigen::Vector3d::Zero());
  pushing_.assign(max_contacts, 0);
  subspace_.setZero(max_contacts, max_contacts);
  subspace_rhs_.setZero(max_contacts);
  sum_.setZero(3 * max_contacts);
}

// The subspace step, on the pushes alone: with every friction and curved-wall impulse held as
// the last sweep left it, the pushing contacts' gaps close together. With x the pushes' changes
// (the impulse change -n x per contact) and d the motion now:
//   n_a'(d_a - sum_b W_ab n_b x_b) + gap_a = 0   for every pushing contact a
// i.e. N' W N x = N' d + gap: symmetric, positive definite where the rows are independent
// (Cholesky in place; a relative 1e-10 on the diagonal keeps near-dependent rows solvable). The
// step goes along x as far as no push turns into a pull: along that segment the pushes' quadratic
// falls all the way to its minimum at 1. (Solving the stuck contacts' whole motion too, or the
// sliding ones' friction with their push, left sweeps that did not settle; projecting the whole
// answer on the cones instead of stopping short left them far worse off than before the step.)
bool ContactPgs::subspace_step(const Eigen::Ref<const Eigen::MatrixXd>& w, std::span<const NodeContact> c,
                               std::span<Eigen::Vector3d> impulses) {
  const int k = static_cast<int>(c.size());
  // (a push far below the largest, 1e-160 N s^2 seen, would stop the step before it began: held)
  double largest = 0.0;
  for (int a = 0; a < k; ++a) largest = std::max(largest, -c[a].normal.dot(impulses[a]));
  int pushing = 0;
  for (int a = 0; a < k; ++a)
    if (-c[a].normal.dot(impulses[a]) > 1e-9 * largest) pushing_[pushing++] = a;
  if (pushing == 0) return false;
  Eigen::Map<Eigen::VectorXd> motion(motion_.front().data(), 3 * k);
  bool moved = false;
  for (int round = 0; round < kSubspaceRounds && pushing > 0; ++round) {
    double diagonal = 0.0;
    for (int p = 0; p < pushing; ++p) {
      const int a = pushing_[p];
      const Eigen::Vector3d& n = c[a].normal;
      for (int q = 0; q <= p; ++q)
        subspace_(p, q) = n.dot(w.block<3, 3>(3 * a, 3 * pushing_[q]) * c[pushing_[q]].normal);
      subspace_rhs_(p) = n.dot(motion_[a]) + c[a].gap_m;
      diagonal = std::max(diagonal, subspace_(p, p));
    }
    Eigen::Ref<Eigen::MatrixXd> system(subspace_.topLeftCorner(pushing, pushing));
    system.diagonal().array() += 1e-10 * diagonal;
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(system);
    if (llt.info() != Eigen::Success) break;
    auto x = subspace_rhs_.head(pushing);
    llt.solveInPlace(x);
    if (!x.allFinite()) break;
    // as far as no push turns into a pull; the one that would is let go and the rest solved again
    double step = 1.0;
    int blocking = -1;
    for (int p = 0; p < pushing; ++p) {
      const double push = std::max(0.0, -c[pushing_[p]].normal.dot(impulses[pushing_[p]]));
      if (x(p) < 0.0 && push < step * -x(p)) {
        step = push / -x(p);
        blocking = p;
      }
    }
    for (int p = 0; p < pushing; ++p) impulses[pushing_[p]] -= step * x(p) * c[pushing_[p]].normal;
    if (blocking >= 0) {
      const int a = pushing_[blocking];
      impulses[a] -= c[a].normal.dot(impulses[a]) * c[a].normal;  // exactly no push
      // (kept in the chain's order: the same answer in any order but for rounding, and the runs
      // are chaotic at round-off; unsorted, single rows of pcisim-bench wire-force moved by 5 %)
      pushing_[blocking] = pushing_[--pushing];
      std::sort(pushing_.begin(), pushing_.begin() + pushing);
    }
    // every node's motion from the impulses and the curved walls' ones
    for (int a = 0; a < k; ++a) sum_.segment<3>(3 * a) = impulses[a] + curvature_[a];
    motion.noalias() = w * sum_.head(3 * k);
    moved = true;
    if (blocking < 0) break;
  }
  return moved;
}

ContactSolveStats ContactPgs::solve(const Eigen::Ref<const Eigen::MatrixXd>& w, std::span<const NodeContact> c,
                                    std::span<Eigen::Vector3d> impulses, int max_sweeps, double tolerance_m) {
  const int k = static_cast<int>(c.size());
  ContactSolveStats stats;
  if (k > max_contacts() || static_cast<int>(impulses.size()) != k || w.rows() != 3 * k || w.cols() != 3 * k)
    throw std::invalid_argument("contact solve: sizes do not match");
  // d = W L from the warm start (the curved walls' impulses start from none)
  // (the 3-vectors lie back to back: seen as one column of 3k, the products are matrix-vector
  // ones, which is where a sweep spends its time)
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double));
  Eigen::Map<Eigen::VectorXd> motion(k > 0 ? motion_.front().data() : nullptr, 3 * k);
  for (int a = 0; a < k; ++a) curvature_[a].setZero();
  if (k > 0) motion.noalias() = w * Eigen::Map<const Eigen::VectorXd>(impulses.front().data(), 3 * k);
  // (without friction the sweeps minimise a convex quadratic, contact by contact, but for a
  // curved wall's impulse: under-relaxing them only slowed them; end on, it buckled a column 10 %
  // early)
  bool may_relax = false;
  for (int a = 0; a < k; ++a) may_relax = may_relax || c[a].mu_static > 0.0 || c[a].mu_kinetic > 0.0;
  may_relax = may_relax && relax_;
  double relaxation = 1.0;
  // one contact's impulse changes by dl: every node's motion follows its column of W
  auto apply = [&](int a, const Eigen::Vector3d& dl) {
    impulses[a] += dl;
    motion.noalias() += w.middleCols<3>(3 * a) * dl;
  };
  // one sweep over the contacts; returns the largest motion an update made. Each contact's
  // normal row, then its tangent rows against its own motion so far; the other nodes' motion
  // follows once per contact
  auto sweep = [&]() {
    double change = 0.0;
    for (int a = 0; a < k; ++a) {
      const NodeContact& ca = c[a];
      const Eigen::Vector3d& n = ca.normal;
      const Eigen::Matrix3d waa = w.block<3, 3>(3 * a, 3 * a);
      const Eigen::Vector3d start = impulses[a];
      // frictionless on a curved wall: the push and the wall's impulse together
      if (ca.mu_static == 0.0 && ca.mu_kinetic == 0.0 && !ca.shape_per_m.isZero(0.0)) {
        Eigen::Vector3d t1, t2;
        tangent_basis(n, &t1, &t2);
        Eigen::Matrix<double, 3, 2> t;
        t << t1, t2;
        const Eigen::Vector3d own = impulses[a] + curvature_[a];
        const Eigen::Vector3d m0 = motion_[a] - waa * own;
        Eigen::Vector2d c_t;
        const double l_n =
            push_on_curved_wall(ca.gap_m + n.dot(m0), n.dot(waa * n), t.transpose() * (waa.transpose() * n),
                                t.transpose() * (waa * n), t.transpose() * waa * t, t.transpose() * ca.shape_per_m * t,
                                t.transpose() * (m0 - ca.linearised_at_m), &c_t);
        const Eigen::Vector3d push_new = -l_n * n, c_new = t * c_t;
        const Eigen::Vector3d dl = relaxation * (push_new + c_new - own);
        change = std::max(change, (waa * (push_new + c_new - own)).norm());
        impulses[a] += relaxation * (push_new - impulses[a]);
        curvature_[a] += relaxation * (c_new - curvature_[a]);
        if (dl.squaredNorm() > 0.0) motion.noalias() += w.middleCols<3>(3 * a) * dl;
        continue;
      }
      // normal: the push that closes the gap, never a pull
      const double w_nn = n.dot(waa * n);
      const double l_n = -n.dot(impulses[a]);
      const double l_n_new = std::max(0.0, l_n + (ca.gap_m + n.dot(motion_[a])) / w_nn);
      Eigen::Vector3d own_motion = motion_[a];
      if (l_n_new != l_n) {
        const Eigen::Vector3d dl = -(l_n_new - l_n) * n;
        impulses[a] += dl;
        own_motion += waa * dl;
        change = std::max(change, std::abs(l_n_new - l_n) * w_nn);
      }
      // apart, and no friction or curved wall's impulse left to take back: nothing more changes
      // (most candidates of a wire along a wall, each sweep)
      if (l_n_new == 0.0 && l_n == 0.0 && impulses[a].squaredNorm() == 0.0 && curvature_[a].squaredNorm() == 0.0)
        continue;
      // tangent: the impulse that stops the slip, inside the static cone; else the kinetic one
      // against the slip that is left. A curved wall's impulse C = -L_n S_tt t'(d - d_0) shares
      // the plane: stuck, the node's motion along the wall is known (it stops the slip), so C is
      // too and friction holds the rest; sliding, C is found after friction with its own motion
      // taken implicitly (W_tt K reaches thousands: a tip pressed into a rounded end is far
      // stiffer sideways there than its rod, and alternating the two rules crept by 1 / (1 + W_tt K)
      // a sweep)
      Eigen::Vector3d t1, t2;
      tangent_basis(n, &t1, &t2);
      Eigen::Matrix<double, 3, 2> t;
      t << t1, t2;
      const Eigen::Vector2d l_t = t.transpose() * impulses[a];
      const Eigen::Vector2d c_old = t.transpose() * curvature_[a];
      const Eigen::Matrix2d w_tt = t.transpose() * waa * t;
      const Eigen::Matrix2d k_tt = l_n_new * (t.transpose() * ca.shape_per_m * t);
      const Eigen::Matrix2d m = w_tt.inverse();
      // the slip without this contact's friction (the curved wall's impulse as it stands)
      const Eigen::Vector2d slip_without = t.transpose() * (ca.slip_m + own_motion) - w_tt * l_t;
      // stuck: d_t = -t' slip, C = -K (d_t - t' d_0), friction = what stops the slip less C
      const Eigen::Vector2d c_stuck = -k_tt * (-t.transpose() * ca.slip_m - t.transpose() * ca.linearised_at_m);
      Eigen::Vector2d l_t_new = -(m * (slip_without - w_tt * c_old)) - c_stuck;
      Eigen::Vector2d c_new = c_stuck;
      const bool stuck = l_t_new.norm() <= l_n_new * ca.mu_static;
      if (!stuck)
        l_t_new = l_n_new > 0.0 && ca.mu_kinetic > 0.0 ? slide_on_cone(m, slip_without, l_n_new * ca.mu_kinetic)
                                                       : Eigen::Vector2d::Zero();
      const Eigen::Vector2d dl_t = l_t_new - l_t;
      if (dl_t.squaredNorm() > 0.0) {
        impulses[a] += t * dl_t;
        change = std::max(change, (w_tt * dl_t).norm());
      }
      if (!stuck) {
        // sliding: C with its own motion taken implicitly, the node's other motion as it stands
        const Eigen::Vector3d moved = motion_[a] + waa * (impulses[a] - start);
        const Eigen::Vector2d s_c = t.transpose() * (moved - ca.linearised_at_m) - w_tt * c_old;
        c_new = -(Eigen::Matrix2d::Identity() + k_tt * w_tt).inverse() * (k_tt * s_c);
      }
      const Eigen::Vector3d dc = t * (c_new - c_old);
      if (dc.squaredNorm() > 0.0) {
        curvature_[a] += dc;
        change = std::max(change, (w_tt * (c_new - c_old)).norm());
      }
      // (under-relaxed, the contact's impulses move that part of the way towards their update. A
      // push that lets go then shrinks geometrically instead of vanishing, its friction with it;
      // letting it go whole, or taking every push whole and relaxing friction alone, cycled on
      // ContactPgs.SweepsThatCycleConvergeUnderRelaxed's problem, and the former made the dead end
      // 2-3 times slower)
      const Eigen::Vector3d dl = relaxation * (impulses[a] - start + dc);
      impulses[a] = start;
      if (dl.squaredNorm() > 0.0) apply(a, dl);
      impulses[a] -= relaxation * dc;
      curvature_[a] -= (1.0 - relaxation) * dc;
    }
    return change;
  };
  // the largest change over the last kRelaxationWindow sweeps, and over the window before
  double window_change = 0.0, previous_window = std::numeric_limits<double>::infinity();
  for (int sweep_count = 0; sweep_count < max_sweeps; ++sweep_count) {
    const double change = sweep();
    stats.sweeps = sweep_count + 1;
    stats.last_change_m = change;
    if (change <= tolerance_m) {
      stats.converged = true;
      break;
    }
    // a window that changed as much as the one before: the sweeps cycle; under-relax them
    window_change = std::max(window_change, change);
    if ((sweep_count + 1) % kRelaxationWindow == 0) {
      if (may_relax && window_change >= previous_window && relaxation > kLeastRelaxation) relaxation *= 0.5;
      previous_window = window_change;
      window_change = 0.0;
    }
    if (sweeps_per_subspace_ > 0 && (sweep_count + 1) % sweeps_per_subspace_ == 0 && sweep_count + 1 < max_sweeps)
      stats.subspace_steps += subspace_step(w, c, impulses) ? 1 : 0;
  }
  stats.relaxation = relaxation;
  return stats;
}

}  // namespace pcisim::physics::rod
