#include "physics/pbd/shape_matching_clusters.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "physics/pbd/rotation_extraction.h"

namespace pcisim::physics::pbd {

void ShapeMatchingClusters::add(std::span<const int> members, double compliance_s2, double volume_compliance_per_j) {
  if (members.empty()) throw std::invalid_argument("shape matching: empty cluster");
  if (!(compliance_s2 >= 0.0)) throw std::invalid_argument("shape matching: compliance must be >= 0");
  member_.insert(member_.end(), members.begin(), members.end());
  offset_.push_back(static_cast<int>(member_.size()));
  compliance_s2_.push_back(compliance_s2);
  volume_compliance_per_j_.push_back(std::isfinite(volume_compliance_per_j) ? volume_compliance_per_j : -1.0);
  max_size_ = std::max(max_size_, static_cast<int>(members.size()));
}

void ShapeMatchingClusters::finalize(const Eigen::Matrix3Xd& rest_m, const Eigen::VectorXd& mass_kg) {
  rest_offset_m_.setZero(3, slot_count());
  rest_moment_kg_m2_.assign(count(), 0.0);
  rotation_.assign(count(), Eigen::Matrix3d::Identity());
  right_.assign(count(), Eigen::Matrix3d::Identity());
  rest_aqq_inverse_.assign(count(), Eigen::Matrix3d::Zero());
  any_volume_ = false;
  for (int c = 0; c < count(); ++c) {
    double m_sum = 0.0;
    Eigen::Vector3d cm = Eigen::Vector3d::Zero();
    for (int s = begin(c); s < end(c); ++s) {
      if (member_[s] < 0 || member_[s] >= rest_m.cols()) throw std::out_of_range("shape matching: bad particle index");
      m_sum += mass_kg[member_[s]];
      cm += mass_kg[member_[s]] * rest_m.col(member_[s]);
    }
    if (!(m_sum > 0.0)) throw std::invalid_argument("shape matching: cluster without mass");
    cm /= m_sum;
    for (int s = begin(c); s < end(c); ++s) {
      rest_offset_m_.col(s) = rest_m.col(member_[s]) - cm;
      rest_moment_kg_m2_[c] += mass_kg[member_[s]] * rest_offset_m_.col(s).squaredNorm();
    }
    // the volume needs a rest shape with extent along every axis: a flat or straight cluster
    // (smallest principal moment under 1e-6 of the largest) keeps shape matching only
    Eigen::Matrix3d a_qq = Eigen::Matrix3d::Zero();
    for (int s = begin(c); s < end(c); ++s)
      a_qq.noalias() += mass_kg[member_[s]] * rest_offset_m_.col(s) * rest_offset_m_.col(s).transpose();
    const Eigen::Vector3d moments =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(a_qq, Eigen::EigenvaluesOnly).eigenvalues();
    if (moments[0] > 1e-6 * moments[2]) {
      rest_aqq_inverse_[c] = a_qq.inverse();
    } else {
      volume_compliance_per_j_[c] = -1.0;
    }
    any_volume_ = any_volume_ || volume_compliance_per_j_[c] >= 0.0;
  }
}

// eq 8: the current centre of mass t (nominal masses, so pinned and driven members still count);
// eq 9: A_pq = sum m p q^T (A_qq only matters for the linear blend and the volume). One pass over
// the members: with y = x - x_first (the first member's position, so the sums stay small),
// t = x_first + sum m y / M and A_pq = sum m y q^T - (t - x_first) sum m q^T (sum m q is zero
// up to rounding: q is measured from the rest centre). my_kg_m, mq_kg_m: the sums of m y, m q
void ShapeMatchingClusters::centre_and_moment(int c, const Eigen::Matrix3Xd& x_m, const Eigen::VectorXd& mass_kg,
                                              Eigen::Vector3d* t, Eigen::Matrix3d* a_pq) const {
  const Eigen::Vector3d origin = x_m.col(member_[begin(c)]);
  double m_sum = 0.0;
  Eigen::Vector3d my_kg_m = Eigen::Vector3d::Zero(), mq_kg_m = Eigen::Vector3d::Zero();
  a_pq->setZero();
  for (int s = begin(c); s < end(c); ++s) {
    const double m = mass_kg[member_[s]];
    const Eigen::Vector3d my = m * (x_m.col(member_[s]) - origin);
    const auto q = rest_offset_m_.col(s);
    m_sum += m;
    my_kg_m += my;
    mq_kg_m += m * q;
    a_pq->noalias() += my * q.transpose();
  }
  const Eigen::Vector3d shift_m = my_kg_m / m_sum;
  *t = origin + shift_m;
  a_pq->noalias() -= shift_m * mq_kg_m.transpose();
}

void ShapeMatchingClusters::goals(int c, const Eigen::Matrix3Xd& x_m, const Eigen::VectorXd& mass_kg,
                                  Eigen::Vector3d* goals_m) const {
  Eigen::Vector3d t;
  fit(c, x_m, mass_kg, &t);
  // eq 10: g_i = R (x0_i - x0_cm) + x_cm
  for (int s = begin(c); s < end(c); ++s) goals_m[s - begin(c)] = rotation_[c] * rest_offset_m_.col(s) + t;
}

void ShapeMatchingClusters::fit(int c, const Eigen::Matrix3Xd& x_m, const Eigen::VectorXd& mass_kg,
                                Eigen::Vector3d* t) const {
  Eigen::Matrix3d a_pq;
  centre_and_moment(c, x_m, mass_kg, t, &a_pq);
  rotation_[c] = extract_rotation(a_pq, rotation_[c], rest_moment_kg_m2_[c], &right_[c]);
}

double ShapeMatchingClusters::volume_correction(int c, const Eigen::Matrix3Xd& x_m, const Eigen::VectorXd& mass_kg,
                                                const Eigen::VectorXd& inv_mass_per_kg, double dt_s, double lambda,
                                                Eigen::Vector3d* dx_m) const {
  const double alpha = volume_compliance_per_j_[c];
  if (alpha < 0.0) {
    for (int s = begin(c); s < end(c); ++s) dx_m[s - begin(c)].setZero();
    return 0.0;
  }
  // the linear fit F = A_pq A_qq^-1
  Eigen::Vector3d t;
  Eigen::Matrix3d a_pq;
  centre_and_moment(c, x_m, mass_kg, &t, &a_pq);
  const Eigen::Matrix3d f = a_pq * rest_aqq_inverse_[c];
  // cof(F) = det(F) F^-T, column by column from cross products (defined for a singular F too)
  Eigen::Matrix3d cof;
  cof.col(0) = f.col(1).cross(f.col(2));
  cof.col(1) = f.col(2).cross(f.col(0));
  cof.col(2) = f.col(0).cross(f.col(1));
  const double constraint = f.col(0).dot(cof.col(0)) - 1.0;
  const Eigen::Matrix3d g = cof * rest_aqq_inverse_[c];
  // dx_m holds each member's grad C / m_i = G q_i until the multiplier is known
  double denom = alpha / (dt_s * dt_s);
  for (int s = begin(c); s < end(c); ++s) {
    const int i = member_[s];
    const Eigen::Vector3d gq = g * rest_offset_m_.col(s);
    dx_m[s - begin(c)] = gq;
    denom += inv_mass_per_kg[i] * mass_kg[i] * mass_kg[i] * gq.squaredNorm();
  }
  if (!(denom > 0.0) || !std::isfinite(denom) || !std::isfinite(constraint)) {
    for (int s = begin(c); s < end(c); ++s) dx_m[s - begin(c)].setZero();
    return 0.0;
  }
  const double dl = (-constraint - alpha / (dt_s * dt_s) * lambda) / denom;
  for (int s = begin(c); s < end(c); ++s) {
    const int i = member_[s];
    dx_m[s - begin(c)] *= inv_mass_per_kg[i] * mass_kg[i] * dl;
  }
  return dl;
}

}  // namespace pcisim::physics::pbd
