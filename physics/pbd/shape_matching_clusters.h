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
  // volume_compliance_per_j: the cluster's volume constraint (below) with this compliance (1/J:
  // 1 / (bulk modulus x the cluster's share of the volume)); negative = none
  void add(std::span<const int> members, double compliance_s2, double volume_compliance_per_j = -1.0);
  // rest shape = the given positions; sizes every buffer; nothing is allocated afterwards
  void finalize(const Eigen::Matrix3Xd& rest_m, const Eigen::VectorXd& mass_kg);

  int count() const { return static_cast<int>(compliance_s2_.size()); }
  int slot_count() const { return static_cast<int>(member_.size()); }
  int begin(int c) const { return offset_[c]; }
  int end(int c) const { return offset_[c + 1]; }
  int member(int slot) const { return member_[slot]; }
  int max_size() const { return max_size_; }
  double compliance_s2(int c) const { return compliance_s2_[c]; }
  // negative when the cluster has no volume constraint (none set, or its rest shape is flat)
  double volume_compliance_per_j(int c) const { return volume_compliance_per_j_[c]; }
  bool any_volume() const { return any_volume_; }
  void set_compliance_s2(int c, double value) { compliance_s2_[c] = value; }
  const Eigen::Matrix3d& rotation(int c) const { return rotation_[c]; }
  // the warm start kept by another solver (PbdCudaSolver) between steps
  void set_rotation(int c, const Eigen::Matrix3d& r) const { rotation_[c] = r; }
  const Eigen::Matrix3Xd& rest_offsets_m() const { return rest_offset_m_; }
  double rest_moment_kg_m2(int c) const { return rest_moment_kg_m2_[c]; }
  // (sum m q q^T)^-1 of cluster c at rest: the volume's F = A_pq A_qq^-1
  const Eigen::Matrix3d& rest_aqq_inverse(int c) const { return rest_aqq_inverse_[c]; }

  // eqs 8-10: centre of mass t, A_pq = sum m p q^T, its rotation R, goals g = R q + t for the
  // members of c, written to goals_m[0 .. size). Updates the cluster's remembered rotation.
  void goals(int c, const Eigen::Matrix3Xd& x_m, const Eigen::VectorXd& mass_kg, Eigen::Vector3d* goals_m) const;
  // the same without writing the goals: the centre t and the rotation (rotation(c)); member slot
  // s's goal is rotation(c) * rest_offsets_m().col(s) + t
  void fit(int c, const Eigen::Matrix3Xd& x_m, const Eigen::VectorXd& mass_kg, Eigen::Vector3d* t) const;

  // The cluster's volume, C = det(F) - 1 with F = A_pq A_qq^-1 its best linear fit (Mueller et al.
  // 2005, "Meshless deformations based on shape matching", eq 7), an XPBD constraint of compliance
  // alpha (alpha~ = alpha / dt^2). grad_i C = m_i cof(F) A_qq^-1 q_i (the centre's term sums to
  // zero), so dx_i = w_i grad_i C dlambda, dlambda = (-C - alpha~ lambda) / (sum w |grad C|^2 + alpha~).
  // Writes each member's correction to dx_m[0 .. size) and returns dlambda; 0 (and no correction)
  // when the cluster has no volume constraint or the fit is degenerate.
  double volume_correction(int c, const Eigen::Matrix3Xd& x_m, const Eigen::VectorXd& mass_kg,
                           const Eigen::VectorXd& inv_mass_per_kg, double dt_s, double lambda,
                           Eigen::Vector3d* dx_m) const;

 private:
  void centre_and_moment(int c, const Eigen::Matrix3Xd& x_m, const Eigen::VectorXd& mass_kg, Eigen::Vector3d* t,
                         Eigen::Matrix3d* a_pq) const;

  std::vector<int> offset_{0};
  std::vector<int> member_;
  std::vector<double> compliance_s2_;
  int max_size_ = 0;
  Eigen::Matrix3Xd rest_offset_m_;  // q_i = x0_i - x0_cm per slot (eq 8)
  std::vector<double> rest_moment_kg_m2_;
  std::vector<double> volume_compliance_per_j_;
  std::vector<Eigen::Matrix3d> rest_aqq_inverse_;  // (sum m q q^T)^-1 per cluster
  bool any_volume_ = false;
  mutable std::vector<Eigen::Matrix3d> rotation_;  // a warm-start cache, not part of the state
  mutable std::vector<Eigen::Matrix3d> right_;     // the rotation's SVD warm start (its right vectors)
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
