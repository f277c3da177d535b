#include "haptics/passivity_controller.h"

#include <algorithm>

namespace pcisim::haptics {

double PassivityController::filter(double force, double velocity, double dt_s, double peak) {
  // observer: energy after this tick if the force is displayed unchanged
  const double energy = energy_ + force * velocity * dt_s;
  last_damping_ = 0.0;
  const double v2dt = velocity * velocity * dt_s;
  if (energy < 0.0 && v2dt > 0.0) {
    // controller: damping that brings the observed energy back to zero, within its limit
    last_damping_ = std::min(-energy / v2dt, max_damping_);
    force += last_damping_ * velocity;
  }
  const double displayed = std::clamp(force, -peak, peak);
  energy_ += displayed * velocity * dt_s;
  return force;
}

}  // namespace pcisim::haptics
