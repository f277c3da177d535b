#pragma once
// Time-domain passivity observer and controller for one force channel (Hannaford & Ryu 2002,
// "Time-domain passivity control of haptic interfaces", IEEE T-RA 18(1)). The observer sums the
// energy the trainee has put into the simulation, E = sum f v dt (f: force resisting the motion,
// v: instrument velocity). A passive simulation keeps E >= 0; when E would go negative the
// controller adds just enough damping, alpha = -E / (v^2 dt), to dissipate the excess.

namespace pcisim::haptics {

class PassivityController {
 public:
  explicit PassivityController(double max_damping = 1e9) : max_damping_(max_damping) {}

  // returns the force to display (f plus the damping this tick needs). The observer books the
  // energy of what the trainee will actually feel: the result clamped to +-peak, the limit the
  // caller applies after this (Hannaford & Ryu: the displayed force)
  double filter(double force, double velocity, double dt_s, double peak = 1e300);

  double energy() const { return energy_; }
  double last_damping() const { return last_damping_; }
  void reset() { energy_ = 0.0, last_damping_ = 0.0; }

 private:
  double max_damping_;
  double energy_ = 0.0;
  double last_damping_ = 0.0;
};

}  // namespace pcisim::haptics
