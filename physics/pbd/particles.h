#pragma once
// PBD particles in structure-of-arrays storage, sized once at build time (SI units).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace pcisim::physics::pbd {

enum class ParticleState : uint8_t {
  kFree,         // integrated and projected
  kPinned,       // inverse mass 0, stays where it is
  kDriven,       // inverse mass 0, follows a prescribed trajectory
  kQuarantined,  // went non-finite: frozen at its last finite position
};

struct Particles {
  Eigen::Matrix3Xd position_m;        // x, at the end of the last substep
  Eigen::Matrix3Xd predicted_m;       // x*, being projected
  Eigen::Matrix3Xd velocity_m_per_s;  // v
  Eigen::Matrix3Xd last_finite_m;     // where a quarantined particle freezes
  Eigen::VectorXd mass_kg;            // nominal; still weights shape matching where pinned or driven
  Eigen::VectorXd inv_mass_per_kg;    // effective: 0 when pinned, driven or quarantined
  std::vector<ParticleState> state;

  int size() const { return static_cast<int>(position_m.cols()); }
  void resize(int n);
};

}  // namespace pcisim::physics::pbd
