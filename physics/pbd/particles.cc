#include "physics/pbd/particles.h"

namespace pcisim::physics::pbd {

void Particles::resize(int n) {
  position_m.setZero(3, n);
  predicted_m.setZero(3, n);
  velocity_m_per_s.setZero(3, n);
  last_finite_m.setZero(3, n);
  mass_kg.setZero(n);
  inv_mass_per_kg.setZero(n);
  state.assign(n, ParticleState::kFree);
}

}  // namespace pcisim::physics::pbd
