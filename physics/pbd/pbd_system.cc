#include "physics/pbd/pbd_system.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "physics/pbd/pbd_cuda_solver.h"

namespace pcisim::physics::pbd {

namespace {
void require_building(bool finalized) {
  if (finalized) throw std::logic_error("pbd: the system is finalized; build everything before finalize()");
}
}  // namespace

int PbdSystem::add_particle(const Eigen::Vector3d& position_m, double mass_kg) {
  require_building(finalized_);
  if (!position_m.allFinite() || !(mass_kg > 0.0) || !std::isfinite(mass_kg))
    throw std::invalid_argument("pbd: a particle needs a finite position and a positive mass");
  build_position_m_.push_back(position_m);
  build_mass_kg_.push_back(mass_kg);
  build_state_.push_back(ParticleState::kFree);
  return static_cast<int>(build_position_m_.size()) - 1;
}

void PbdSystem::pin(int i) {
  require_building(finalized_);
  build_state_.at(i) = ParticleState::kPinned;
}

void PbdSystem::drive(int i) {
  require_building(finalized_);
  build_state_.at(i) = ParticleState::kDriven;
}

void PbdSystem::add_distance(int i, int j, double compliance_m_per_n) {
  require_building(finalized_);
  if (i == j || !(compliance_m_per_n >= 0.0)) throw std::invalid_argument("pbd: bad distance constraint");
  distance_.push_back({i, j, (build_position_m_.at(i) - build_position_m_.at(j)).norm(), compliance_m_per_n});
}

void PbdSystem::add_bending(int a, int b, int c, int d, double compliance_per_n_m) {
  require_building(finalized_);
  double theta = 0.0;
  Eigen::Vector3d g[4];
  if (!(compliance_per_n_m >= 0.0) || !dihedral_angle(build_position_m_.at(a), build_position_m_.at(b),
                                                      build_position_m_.at(c), build_position_m_.at(d), &theta, g))
    throw std::invalid_argument("pbd: bending needs two non-degenerate triangles at rest");
  bending_.push_back({a, b, c, d, theta, compliance_per_n_m});
}

void PbdSystem::add_cluster(std::span<const int> members, double compliance_s2, double volume_compliance_per_j) {
  require_building(finalized_);
  clusters_.add(members, compliance_s2, volume_compliance_per_j);
}

void PbdSystem::finalize() {
  require_building(finalized_);
  const int n = static_cast<int>(build_position_m_.size());
  particles_.resize(n);
  for (int i = 0; i < n; ++i) {
    particles_.position_m.col(i) = build_position_m_[i];
    particles_.mass_kg[i] = build_mass_kg_[i];
    particles_.state[i] = build_state_[i];
    particles_.inv_mass_per_kg[i] = build_state_[i] == ParticleState::kFree ? 1.0 / build_mass_kg_[i] : 0.0;
  }
  particles_.predicted_m = particles_.position_m;
  particles_.last_finite_m = particles_.position_m;
  drive_start_m_ = particles_.position_m;
  drive_target_m_ = particles_.position_m;
  clusters_.finalize(particles_.position_m, particles_.mass_kg);
  for (const auto& c : distance_)
    if (c.i < 0 || c.j < 0 || c.i >= n || c.j >= n) throw std::out_of_range("pbd: distance index");

  distance_lambda_.setZero(static_cast<Eigen::Index>(distance_.size()));
  bending_lambda_.setZero(static_cast<Eigen::Index>(bending_.size()));
  cluster_lambda_.setZero(3, clusters_.slot_count());
  volume_lambda_.setZero(clusters_.count());
  goal_scratch_m_.assign(std::max(clusters_.max_size(), 1), Eigen::Vector3d::Zero());

  std::vector<int> slots;
  for (const auto& c : distance_) slots.insert(slots.end(), {c.i, c.j});
  distance_group_.build(n, slots);
  slots.clear();
  for (const auto& c : bending_) slots.insert(slots.end(), {c.a, c.b, c.c, c.d});
  bending_group_.build(n, slots);
  slots.clear();
  for (int s = 0; s < clusters_.slot_count(); ++s) slots.push_back(clusters_.member(s));
  cluster_group_.build(n, slots);

  distance_mean_inv_count_.setZero(static_cast<Eigen::Index>(distance_.size()));
  for (size_t k = 0; k < distance_.size(); ++k)
    distance_mean_inv_count_[k] =
        0.5 * (distance_group_.inverse_count(distance_[k].i) + distance_group_.inverse_count(distance_[k].j));
  bending_mean_inv_count_.setZero(static_cast<Eigen::Index>(bending_.size()));
  for (size_t k = 0; k < bending_.size(); ++k) {
    const auto& c = bending_[k];
    bending_mean_inv_count_[k] = 0.25 * (bending_group_.inverse_count(c.a) + bending_group_.inverse_count(c.b) +
                                         bending_group_.inverse_count(c.c) + bending_group_.inverse_count(c.d));
  }
  distance_min_inv_count_.setZero(static_cast<Eigen::Index>(distance_.size()));
  for (size_t k = 0; k < distance_.size(); ++k)
    distance_min_inv_count_[k] =
        std::min(distance_group_.inverse_count(distance_[k].i), distance_group_.inverse_count(distance_[k].j));
  bending_min_inv_count_.setZero(static_cast<Eigen::Index>(bending_.size()));
  for (size_t k = 0; k < bending_.size(); ++k) {
    const auto& c = bending_[k];
    bending_min_inv_count_[k] = std::min({bending_group_.inverse_count(c.a), bending_group_.inverse_count(c.b),
                                          bending_group_.inverse_count(c.c), bending_group_.inverse_count(c.d)});
  }
  cluster_min_inv_count_.setZero(clusters_.count());
  for (int c = 0; c < clusters_.count(); ++c) {
    double m = 1.0;
    for (int slot = clusters_.begin(c); slot < clusters_.end(c); ++slot)
      m = std::min(m, cluster_group_.inverse_count(clusters_.member(slot)));
    cluster_min_inv_count_[c] = m;
  }
  home_state_ = std::move(build_state_);
  build_position_m_ = {};
  build_mass_kg_ = {};
  build_state_ = {};
  finalized_ = true;
}

void PbdSystem::set_driven_target(int i, const Eigen::Vector3d& position_m) {
  if (!finalized_) throw std::logic_error("pbd: set_driven_target before finalize()");
  if (i < 0 || i >= particle_count() || home_state_[i] != ParticleState::kDriven)
    throw std::invalid_argument("pbd: set_driven_target: particle " + std::to_string(i) + " is not a driven particle");
  drive_target_m_.col(i) = position_m;  // a non-finite target is caught (quarantined) by the next step
}

int PbdSystem::quarantined_now() const {
  return static_cast<int>(std::count(particles_.state.begin(), particles_.state.end(), ParticleState::kQuarantined));
}

void PbdSystem::quarantine(int i, const Eigen::Vector3d& freeze_at_m) {
  // frozen with inverse mass 0: neighbours see a pinned particle, never its NaN
  particles_.position_m.col(i) = freeze_at_m;
  particles_.predicted_m.col(i) = freeze_at_m;
  particles_.velocity_m_per_s.col(i).setZero();
  particles_.inv_mass_per_kg[i] = 0.0;
  particles_.state[i] = ParticleState::kQuarantined;
  ++quarantined_total_;
}

void PbdSystem::release_quarantine() {
  // each particle goes back to what it was built as: free, pinned or driven
  for (int i = 0; i < particle_count(); ++i) {
    if (particles_.state[i] != ParticleState::kQuarantined) continue;
    particles_.state[i] = home_state_[i];
    particles_.inv_mass_per_kg[i] = home_state_[i] == ParticleState::kFree ? 1.0 / particles_.mass_kg[i] : 0.0;
  }
}

void PbdSystem::quarantine_non_finite_inputs() {
  // whatever the caller wrote between steps (positions, velocities, driven targets)
  for (int i = 0; i < particle_count(); ++i) {
    if (particles_.state[i] == ParticleState::kQuarantined) continue;
    const bool bad_target = particles_.state[i] == ParticleState::kDriven && !drive_target_m_.col(i).allFinite();
    if (!particles_.position_m.col(i).allFinite() || !particles_.velocity_m_per_s.col(i).allFinite() || bad_target)
      quarantine(i, particles_.last_finite_m.col(i));
  }
}

void PbdSystem::step(double dt_s, const PbdParams& params, ContactProjector* contacts) {
  if (!finalized_) throw std::logic_error("pbd: finalize() before step()");
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return;
  ContactProjector::DeviceSetup device_contacts;
  if (contacts && params.solver == SolverKind::kJacobiCuda && !contacts->device_setup(&device_contacts))
    throw std::invalid_argument("pbd: these contacts are solved on the CPU only; use kGaussSeidel or kJacobi");
  if (params.solver == SolverKind::kJacobiCuda && !cuda_.solver)
    cuda_.solver = std::make_shared<PbdCudaSolver>(*this);  // throws std::invalid_argument without CUDA
  quarantine_non_finite_inputs();
  if (params.solver == SolverKind::kJacobiCuda) {
    // the same substeps as below, on the device (pbd_cuda_solver.h)
    cuda_.solver->run_step(*this, dt_s, params, contacts);
  } else {
    step_on_cpu(dt_s, params, contacts);
  }
  for (int i = 0; i < particle_count(); ++i)
    if (particles_.state[i] != ParticleState::kQuarantined)
      particles_.last_finite_m.col(i) = particles_.position_m.col(i);
}

void PbdSystem::step_on_cpu(double dt_s, const PbdParams& params, ContactProjector* contacts) {
  const int substeps = std::max(params.substeps, 1);
  const double h = dt_s / substeps;
  drive_start_m_ = particles_.position_m;  // same size: a copy, no allocation
  for (int s = 0; s < substeps; ++s) {
    predict(h, static_cast<double>(s + 1) / substeps, s + 1 == substeps, params);
    if (contacts) contacts->begin_substep(particles_, h, static_cast<double>(s + 1) / substeps);
    distance_lambda_.setZero();
    bending_lambda_.setZero();
    cluster_lambda_.setZero();
    volume_lambda_.setZero();
    for (int it = 0; it < params.iterations; ++it) {
      if (params.solver == SolverKind::kJacobi) {
        // the last iteration is not over-relaxed: an overshoot (1 - w)^k C left in x* becomes a
        // velocity, and for one stiff constraint that step map has an eigenvalue of modulus
        // |r| + sqrt(r^2 + |r|), r = (1 - w)^k, above 1 once r < -1/3 (w = 1.5 with one
        // iteration, w = 1.9 with one or three): the body would gain energy every substep
        solve_jacobi(h, it + 1 == params.iterations ? 1.0 : params.sor_w, params.averaging);
      } else {
        solve_gauss_seidel(h);
      }
      if (contacts) contacts->project(particles_, h);
    }
    if (contacts) contacts->end_substep(particles_, h);
    update(h);
  }
}

// Algorithm 1 lines 1-5: external forces, then x* = x + dt v
void PbdSystem::predict(double h_s, double fraction_of_step, bool last_substep, const PbdParams& params) {
  const double drag = 1.0 / (1.0 + std::max(params.damping_per_s, 0.0) * h_s);
  for (int i = 0; i < particle_count(); ++i) {
    switch (particles_.state[i]) {
      case ParticleState::kFree:
        // drag before gravity, so a body at rest feels all of g (its static sag is exact)
        particles_.velocity_m_per_s.col(i) = drag * particles_.velocity_m_per_s.col(i) + h_s * params.gravity_m_per_s2;
        particles_.predicted_m.col(i) = particles_.position_m.col(i) + h_s * particles_.velocity_m_per_s.col(i);
        break;
      case ParticleState::kDriven:
        // exactly on the target at the step's end, on the straight line before it
        particles_.predicted_m.col(i) =
            last_substep ? Eigen::Vector3d(drive_target_m_.col(i))
                         : Eigen::Vector3d(drive_start_m_.col(i) +
                                           fraction_of_step * (drive_target_m_.col(i) - drive_start_m_.col(i)));
        break;
      case ParticleState::kPinned:
      case ParticleState::kQuarantined:
        particles_.predicted_m.col(i) = particles_.position_m.col(i);
        break;
    }
  }
}

// Algorithm 1 lines 16-22 with each constraint applied as soon as it is solved
void PbdSystem::solve_gauss_seidel(double h_s) {
  Eigen::Matrix3Xd& x = particles_.predicted_m;
  const Eigen::VectorXd& w = particles_.inv_mass_per_kg;
  const double inv_h2 = 1.0 / (h_s * h_s);
  for (size_t k = 0; k < distance_.size(); ++k) {
    const DistanceConstraint& c = distance_[k];
    double dl;
    Eigen::Vector3d dxi, dxj;
    if (!project_distance(x.col(c.i), x.col(c.j), w[c.i], w[c.j], c.rest_m, c.compliance_m_per_n * inv_h2,
                          distance_lambda_[k], &dl, &dxi, &dxj))
      continue;
    distance_lambda_[k] += dl;
    x.col(c.i) += dxi;
    x.col(c.j) += dxj;
  }
  for (size_t k = 0; k < bending_.size(); ++k) {
    const DihedralBendingConstraint& c = bending_[k];
    const int idx[4] = {c.a, c.b, c.c, c.d};
    Eigen::Vector3d xs[4], dx[4];
    double ws[4], dl;
    for (int m = 0; m < 4; ++m) xs[m] = x.col(idx[m]), ws[m] = w[idx[m]];
    if (!project_dihedral_bending(xs, ws, c.rest_angle_rad, c.compliance_per_n_m * inv_h2, bending_lambda_[k], &dl, dx))
      continue;
    bending_lambda_[k] += dl;
    for (int m = 0; m < 4; ++m) x.col(idx[m]) += dx[m];
  }
  for (int cl = 0; cl < clusters_.count(); ++cl) {
    Eigen::Vector3d t;
    clusters_.fit(cl, x, particles_.mass_kg, &t);
    const Eigen::Matrix3d& r = clusters_.rotation(cl);
    for (int s = clusters_.begin(cl); s < clusters_.end(cl); ++s) {
      const int i = clusters_.member(s);
      const Eigen::Vector3d goal = r * clusters_.rest_offsets_m().col(s) + t;
      Eigen::Vector3d dl, dx;
      if (!project_to_goal(x.col(i), goal, w[i], particles_.mass_kg[i], clusters_.compliance_s2(cl), h_s,
                           cluster_lambda_.col(s), &dl, &dx))
        continue;
      cluster_lambda_.col(s) += dl;
      x.col(i) += dx;
    }
    if (clusters_.volume_compliance_per_j(cl) >= 0.0) {
      volume_lambda_[cl] +=
          clusters_.volume_correction(cl, x, particles_.mass_kg, w, h_s, volume_lambda_[cl], goal_scratch_m_.data());
      for (int s = clusters_.begin(cl); s < clusters_.end(cl); ++s)
        x.col(clusters_.member(s)) += goal_scratch_m_[s - clusters_.begin(cl)];
    }
  }
}

// Algorithm 1 lines 17-21: per group, every constraint reads the same x*, corrections are
// averaged per particle and over-relaxed by w (eq 7). lambda accumulates the share of dlambda
// that the averaging actually delivered (w/n), so the compliance term sees the applied force.
// Per-constraint averaging scales a constraint's slots by 1/max n of its particles instead.
void PbdSystem::solve_jacobi(double h_s, double sor_w, JacobiAveraging averaging) {
  const bool per_particle = averaging == JacobiAveraging::kPerParticle;
  Eigen::Matrix3Xd& x = particles_.predicted_m;
  const Eigen::VectorXd& w = particles_.inv_mass_per_kg;
  const double inv_h2 = 1.0 / (h_s * h_s);
  if (!distance_.empty()) {
    Eigen::Matrix3Xd& slot = distance_group_.slots();
    for (size_t k = 0; k < distance_.size(); ++k) {
      const DistanceConstraint& c = distance_[k];
      double dl;
      Eigen::Vector3d dxi, dxj;
      if (project_distance(x.col(c.i), x.col(c.j), w[c.i], w[c.j], c.rest_m, c.compliance_m_per_n * inv_h2,
                           distance_lambda_[k], &dl, &dxi, &dxj)) {
        const double share = per_particle ? 1.0 : distance_min_inv_count_[k];
        distance_lambda_[k] += sor_w * (per_particle ? distance_mean_inv_count_[k] : share) * dl;
        slot.col(2 * k) = share * dxi;
        slot.col(2 * k + 1) = share * dxj;
      } else {
        slot.col(2 * k).setZero();
        slot.col(2 * k + 1).setZero();
      }
    }
    distance_group_.apply(x, sor_w, per_particle);
  }
  if (!bending_.empty()) {
    Eigen::Matrix3Xd& slot = bending_group_.slots();
    for (size_t k = 0; k < bending_.size(); ++k) {
      const DihedralBendingConstraint& c = bending_[k];
      const int idx[4] = {c.a, c.b, c.c, c.d};
      Eigen::Vector3d xs[4], dx[4];
      double ws[4], dl;
      for (int m = 0; m < 4; ++m) xs[m] = x.col(idx[m]), ws[m] = w[idx[m]];
      const bool ok = project_dihedral_bending(xs, ws, c.rest_angle_rad, c.compliance_per_n_m * inv_h2,
                                               bending_lambda_[k], &dl, dx);
      const double share = per_particle ? 1.0 : bending_min_inv_count_[k];
      if (ok) bending_lambda_[k] += sor_w * (per_particle ? bending_mean_inv_count_[k] : share) * dl;
      for (int m = 0; m < 4; ++m) slot.col(4 * k + m) = ok ? Eigen::Vector3d(share * dx[m]) : Eigen::Vector3d::Zero();
    }
    bending_group_.apply(x, sor_w, per_particle);
  }
  if (clusters_.count() > 0) {
    Eigen::Matrix3Xd& slot = cluster_group_.slots();
    for (int cl = 0; cl < clusters_.count(); ++cl) {
      // a parallel version gives each worker its own goal scratch
      clusters_.goals(cl, x, particles_.mass_kg, goal_scratch_m_.data());
      const double share = per_particle ? 1.0 : cluster_min_inv_count_[cl];
      for (int s = clusters_.begin(cl); s < clusters_.end(cl); ++s) {
        const int i = clusters_.member(s);
        Eigen::Vector3d dl, dx;
        if (project_to_goal(x.col(i), goal_scratch_m_[s - clusters_.begin(cl)], w[i], particles_.mass_kg[i],
                            clusters_.compliance_s2(cl), h_s, cluster_lambda_.col(s), &dl, &dx)) {
          cluster_lambda_.col(s) += (sor_w * (per_particle ? cluster_group_.inverse_count(i) : share)) * dl;
          slot.col(s) = share * dx;
        } else {
          slot.col(s).setZero();
        }
      }
    }
    cluster_group_.apply(x, sor_w, per_particle);
  }
  if (clusters_.any_volume()) {
    // the volumes as one more group over the same slots, reading the positions the shapes left
    Eigen::Matrix3Xd& slot = cluster_group_.slots();
    for (int cl = 0; cl < clusters_.count(); ++cl) {
      const double dl =
          clusters_.volume_correction(cl, x, particles_.mass_kg, w, h_s, volume_lambda_[cl], goal_scratch_m_.data());
      const double share = per_particle ? 1.0 : cluster_min_inv_count_[cl];
      // the multiplier takes the share the averaging delivers (the cluster's mean 1/n per particle)
      double delivered = share;
      if (per_particle) {
        delivered = 0.0;
        for (int s = clusters_.begin(cl); s < clusters_.end(cl); ++s)
          delivered += cluster_group_.inverse_count(clusters_.member(s));
        delivered /= clusters_.end(cl) - clusters_.begin(cl);
      }
      volume_lambda_[cl] += sor_w * delivered * dl;
      for (int s = clusters_.begin(cl); s < clusters_.end(cl); ++s)
        slot.col(s) = share * goal_scratch_m_[s - clusters_.begin(cl)];
    }
    cluster_group_.apply(x, sor_w, per_particle);
  }
}

// Algorithm 1 lines 23-26, with the NaN guard: a particle whose x* went non-finite is frozen
// where this substep began instead of handing its NaN to the velocity and the next substep
void PbdSystem::update(double h_s) {
  const double inv_h = 1.0 / h_s;
  for (int i = 0; i < particle_count(); ++i) {
    if (!particles_.predicted_m.col(i).allFinite()) {
      quarantine(i, particles_.position_m.col(i));
      continue;
    }
    particles_.velocity_m_per_s.col(i) = inv_h * (particles_.predicted_m.col(i) - particles_.position_m.col(i));
    particles_.position_m.col(i) = particles_.predicted_m.col(i);
  }
}

}  // namespace pcisim::physics::pbd
