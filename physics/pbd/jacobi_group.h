#pragma once
// Parallel Jacobi for one constraint group (soft-tissue paper eq 7, Algorithm 1 lines 17-21):
// every constraint of the group reads the same positions and writes its corrections into its
// own slots; each particle then moves by w * (sum of its slots) / n. Writers never share a slot
// and the gather reads only its own particle's slots, so both loops can run in parallel without
// atomics (no threads here yet: physics/ stays single-threaded).
#include <Eigen/Core>
#include <span>
#include <vector>

namespace pcisim::physics::pbd {

class JacobiGroup {
 public:
  // slot_particle[s]: the particle that slot s moves
  void build(int particle_count, std::span<const int> slot_particle);

  Eigen::Matrix3Xd& slots() { return slot_dx_m_; }
  // 1/n for the particle: the averaging weight (0 when no slot touches it)
  double inverse_count(int particle) const { return inverse_count_[particle]; }
  // x_i += w * sum_slots(i) / n_i (SOR over the averaged corrections), w in [1, 2]; without
  // divide_by_count the slots were already scaled by their constraint and x_i += w * sum_slots(i)
  void apply(Eigen::Matrix3Xd& x_m, double sor_w, bool divide_by_count = true) const;

  // the CSR layout, for twins that gather in the same order (PbdCudaSolver)
  std::span<const int> offsets() const { return offset_; }
  std::span<const int> slot_order() const { return slot_; }
  std::span<const double> inverse_counts() const { return inverse_count_; }

 private:
  Eigen::Matrix3Xd slot_dx_m_;
  std::vector<int> offset_;  // CSR: particle -> its slots
  std::vector<int> slot_;
  std::vector<double> inverse_count_;
};

}  // namespace pcisim::physics::pbd
