#include "physics/pbd/jacobi_group.h"

namespace pcisim::physics::pbd {

void JacobiGroup::build(int particle_count, std::span<const int> slot_particle) {
  slot_dx_m_.setZero(3, static_cast<Eigen::Index>(slot_particle.size()));
  offset_.assign(particle_count + 1, 0);
  for (int p : slot_particle) ++offset_[p + 1];
  for (int i = 0; i < particle_count; ++i) offset_[i + 1] += offset_[i];
  slot_.assign(slot_particle.size(), 0);
  std::vector<int> fill(offset_.begin(), offset_.end() - 1);
  for (int s = 0; s < static_cast<int>(slot_particle.size()); ++s) slot_[fill[slot_particle[s]]++] = s;
  inverse_count_.assign(particle_count, 0.0);
  for (int i = 0; i < particle_count; ++i) {
    const int n = offset_[i + 1] - offset_[i];
    inverse_count_[i] = n > 0 ? 1.0 / n : 0.0;
  }
}

void JacobiGroup::apply(Eigen::Matrix3Xd& x_m, double sor_w, bool divide_by_count) const {
  const int n = static_cast<int>(inverse_count_.size());
  for (int i = 0; i < n; ++i) {
    if (offset_[i] == offset_[i + 1]) continue;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = offset_[i]; k < offset_[i + 1]; ++k) sum += slot_dx_m_.col(slot_[k]);
    x_m.col(i) += (divide_by_count ? sor_w * inverse_count_[i] : sor_w) * sum;
  }
}

}  // namespace pcisim::physics::pbd
