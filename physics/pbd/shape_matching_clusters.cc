#include "physics/pbd/shape_matching_clusters.h"

#include <algorithm>
#include <stdexcept>

#include "physics/pbd/rotation_extraction.h"

namespace pcisim::physics::pbd {

void ShapeMatchingClusters::add(std::span<const int> members, double compliance_s2) {
  if (members.empty()) throw std::invalid_argument("shape matching: empty cluster");
  if (!(compliance_s2 >= 0.0)) throw std::invalid_argument("shape matching: compliance must be >= 0");
  member_.insert(member_.end(), members.begin(), members.end());
  offset_.push_back(static_cast<int>(member_.size()));
  compliance_s2_.push_back(compliance_s2);
  max_size_ = std::max(max_size_, static_cast<int>(members.size()));
}

void ShapeMatchingClusters::finalize(const Eigen::Matrix3Xd& rest_m, const Eigen::VectorXd& mass_kg) {
  rest_offset_m_.setZero(3, slot_count());
  rest_moment_kg_m2_.assign(count(), 0.0);
  rotation_.assign(count(), Eigen::Matrix3d::Identity());
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
  }
}

void ShapeMatchingClusters::goals(int c, const Eigen::Matrix3Xd& x_m, const Eigen::VectorXd& mass_kg,
                                  Eigen::Vector3d* goals_m) const {
  // eq 8: current centre of mass t (nominal masses, so pinned and driven members still count)
  double m_sum = 0.0;
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  for (int s = begin(c); s < end(c); ++s) {
    m_sum += mass_kg[member_[s]];
    t += mass_kg[member_[s]] * x_m.col(member_[s]);
  }
  t /= m_sum;
  // eq 9: A_pq = sum m p q^T; A_qq only matters for the linear (non-rigid) blend, not used here
  Eigen::Matrix3d a_pq = Eigen::Matrix3d::Zero();
  for (int s = begin(c); s < end(c); ++s)
    a_pq.noalias() += mass_kg[member_[s]] * (x_m.col(member_[s]) - t) * rest_offset_m_.col(s).transpose();
  rotation_[c] = extract_rotation(a_pq, rotation_[c], rest_moment_kg_m2_[c]);
  // eq 10: g_i = R (x0_i - x0_cm) + x_cm
  for (int s = begin(c); s < end(c); ++s) goals_m[s - begin(c)] = rotation_[c] * rest_offset_m_.col(s) + t;
}

}  // namespace pcisim::physics::pbd
