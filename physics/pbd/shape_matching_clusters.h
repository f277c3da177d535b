#pragma once
// Shape matching over overlapping clusters of particles (heart paper eqs 7-10; soft-tissue paper
// eqs 8-9 and 12). One cluster holding every particle is global shape matching.
#include <Eigen/Core>
#include <span>
#include <vector>

namespace pcisim::physics::pbd {

class ShapeMatchingClusters {
 public:
  // build time. compliance_s2 = 1/omega^2 of the pull toward the goal (0 = rigid cluster)
  void add(std::span<const int> members, double compliance_s2);
  // rest shape = the given positions; sizes every buffer; nothing is allocated afterwards
  void finalize(const Eigen::Matrix3Xd& rest_m, const Eigen::VectorXd& mass_kg);

  int count() const { return static_cast<int>(compliance_s2_.size()); }
  int slot_count() const { return static_cast<int>(member_.size()); }
  int begin(int c) const { return offset_[c]; }
  int end(int c) const { return offset_[c + 1]; }
  int member(int slot) const { return member_[slot]; }
  int max_size() const { return max_size_; }
  double compliance_s2(int c) const { return compliance_s2_[c]; }
  void set_compliance_s2(int c, double value) { compliance_s2_[c] = value; }
  const Eigen::Matrix3d& rotation(int c) const { return rotation_[c]; }
  // the warm start kept by another solver (PbdCudaSolver) between steps
  void set_rotation(int c, const Eigen::Matrix3d& r) const { rotation_[c] = r; }
  const Eigen::Matrix3Xd& rest_offsets_m() const { return rest_offset_m_; }
  double rest_moment_kg_m2(int c) const { return rest_moment_kg_m2_[c]; }

  // eqs 8-10: centre of mass t, A_pq = sum m p q^T, its rotation R, goals g = R q + t for the
  // members of c, written to goals_m[0 .. size). Updates the cluster's remembered rotation.
  void goals(int c, const Eigen::Matrix3Xd& x_m, const Eigen::VectorXd& mass_kg, Eigen::Vector3d* goals_m) const;

 private:
  std::vector<int> offset_{0};
  std::vector<int> member_;
  std::vector<double> compliance_s2_;
  int max_size_ = 0;
  Eigen::Matrix3Xd rest_offset_m_;  // q_i = x0_i - x0_cm per slot (eq 8)
  std::vector<double> rest_moment_kg_m2_;
  mutable std::vector<Eigen::Matrix3d> rotation_;  // a warm-start cache, not part of the state
};

// Soft-tissue paper eq 12 as an XPBD constraint C = x_i - g_i with g held fixed, compliance
// scaled by 1/m_i so the pull is mass-independent: alpha~ = alpha / (m_i dt^2). With one
// iteration and lambda = 0 this is dx = k (g - x), k = 1 / (1 + alpha/dt^2): the paper's
// stiffness alpha in [0, 1], but no longer tied to dt and iteration count.
inline bool project_to_goal(const Eigen::Vector3d& x, const Eigen::Vector3d& goal, double w, double mass_kg,
                            double compliance_s2, double dt_s, const Eigen::Vector3d& lambda, Eigen::Vector3d* dlambda,
                            Eigen::Vector3d* dx) {
  const double alpha_tilde = compliance_s2 / (mass_kg * dt_s * dt_s);
  const double denom = w + alpha_tilde;
  if (!(denom > 0.0)) return false;
  const Eigen::Vector3d dl = (goal - x - alpha_tilde * lambda) / denom;
  if (!dl.allFinite()) return false;
  *dlambda = dl;
  *dx = w * dl;
  return true;
}

}  // namespace pcisim::physics::pbd
