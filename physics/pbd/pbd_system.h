#pragma once
// A position-based dynamics body: particles, constraints and the predict-project-update step
// (soft-tissue paper Algorithm 1), Gauss-Seidel or parallel Jacobi with SOR, XPBD compliance.
// Build with add_*, then finalize() sizes every buffer; step() allocates nothing.
#include <Eigen/Core>
#include <memory>
#include <span>
#include <vector>

#include "physics/pbd/contact_projector.h"
#include "physics/pbd/dihedral_bending_constraint.h"
#include "physics/pbd/distance_constraint.h"
#include "physics/pbd/jacobi_group.h"
#include "physics/pbd/particles.h"
#include "physics/pbd/pbd_params.h"
#include "physics/pbd/shape_matching_clusters.h"

namespace pcisim::physics::pbd {

class PbdCudaSolver;

class PbdSystem {
 public:
  // --- build time ---
  int add_particle(const Eigen::Vector3d& position_m, double mass_kg);
  void pin(int i);    // inverse mass 0, stays put
  void drive(int i);  // inverse mass 0, follows set_driven_target
  // rest values are taken from the positions at the time of the call
  void add_distance(int i, int j, double compliance_m_per_n);
  void add_bending(int a, int b, int c, int d, double compliance_per_n_m);  // hinge a-b, wings c, d
  // volume_compliance_per_j >= 0 adds the cluster's volume constraint (shape_matching_clusters.h)
  void add_cluster(std::span<const int> members, double compliance_s2, double volume_compliance_per_j = -1.0);
  void finalize();
  bool finalized() const { return finalized_; }

  // --- run time ---
  // where driven particle i is at the end of the next step; substeps move it on the straight
  // line from where it is, so it arrives there exactly
  void set_driven_target(int i, const Eigen::Vector3d& position_m);
  // contacts (optional, not owned) are called inside each substep (contact_projector.h); with
  // kJacobiCuda they are solved on the device, and contacts whose device_setup() is false throw
  // std::invalid_argument
  void step(double dt_s, const PbdParams& params, ContactProjector* contacts = nullptr);
  // quarantined particles return to what they were built as (free, pinned or driven), from where
  // they froze (the provocation is over); a driven one heads for its target again
  void release_quarantine();

  int particle_count() const { return particles_.size(); }
  const Particles& particles() const { return particles_; }
  Particles& particles() { return particles_; }  // positions and velocities may be edited between steps
  const std::vector<DistanceConstraint>& distance_constraints() const { return distance_; }
  const std::vector<DihedralBendingConstraint>& bending_constraints() const { return bending_; }
  const ShapeMatchingClusters& clusters() const { return clusters_; }
  ShapeMatchingClusters& clusters() { return clusters_; }
  long quarantined_total() const { return quarantined_total_; }  // since build
  int quarantined_now() const;
  // the device twin that SolverKind::kJacobiCuda built on its first step (null before; a copy
  // of the system starts without one and builds its own)
  const PbdCudaSolver* cuda_solver() const { return cuda_.solver.get(); }

 private:
  friend class PbdCudaSolver;
  // owns the lazily built CUDA solver; copies start empty so PbdSystem stays copyable
  struct CudaSlot {
    std::shared_ptr<PbdCudaSolver> solver;
    CudaSlot() = default;
    CudaSlot(const CudaSlot&) {}
    CudaSlot& operator=(const CudaSlot&) {
      solver.reset();
      return *this;
    }
    CudaSlot(CudaSlot&&) = default;
    CudaSlot& operator=(CudaSlot&&) = default;
  };

  void quarantine(int i, const Eigen::Vector3d& freeze_at_m);
  void quarantine_non_finite_inputs();
  void step_on_cpu(double dt_s, const PbdParams& params, ContactProjector* contacts);
  void predict(double h_s, double fraction_of_step, bool last_substep, const PbdParams& params);
  void solve_gauss_seidel(double h_s);
  void solve_jacobi(double h_s, double sor_w, JacobiAveraging averaging);
  void update(double h_s);

  bool finalized_ = false;
  Particles particles_;
  std::vector<Eigen::Vector3d> build_position_m_;
  std::vector<double> build_mass_kg_;
  std::vector<ParticleState> build_state_;
  std::vector<ParticleState> home_state_;  // the built state of each particle, for release_quarantine

  std::vector<DistanceConstraint> distance_;
  std::vector<DihedralBendingConstraint> bending_;
  ShapeMatchingClusters clusters_;

  // XPBD multipliers, reset every substep
  Eigen::VectorXd distance_lambda_, bending_lambda_;
  Eigen::Matrix3Xd cluster_lambda_;  // one 3-vector per cluster slot
  Eigen::VectorXd volume_lambda_;    // one per cluster

  // Jacobi: one group per constraint type, and how much of each dlambda the averaging delivers
  JacobiGroup distance_group_, bending_group_, cluster_group_;
  Eigen::VectorXd distance_mean_inv_count_, bending_mean_inv_count_;
  // 1 / (largest count among the constraint's particles), for JacobiAveraging::kPerConstraint
  Eigen::VectorXd distance_min_inv_count_, bending_min_inv_count_, cluster_min_inv_count_;

  std::vector<Eigen::Vector3d> goal_scratch_m_;  // one cluster's goals
  Eigen::Matrix3Xd drive_start_m_, drive_target_m_;
  long quarantined_total_ = 0;
  CudaSlot cuda_;
};

}  // namespace pcisim::physics::pbd
