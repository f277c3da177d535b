#pragma once
// One 1 kHz tick of force: fill the time between physics results (local model with blending,
// zero-order hold or linear extrapolation), then apply the safety layers in a fixed order:
// NaN guard -> fade (stale model / silent instrument) or ramp-in -> slew -> passivity -> clamp.
// Plain arithmetic on preallocated state: no allocation, lock, log or syscall.
#include <cstdint>

#include "haptics/haptic_params.h"
#include "haptics/passivity_controller.h"
#include "physics/local_force_model.h"

namespace pcisim::haptics {

struct InstrumentSample {
  int64_t received_us = 0;  // monotonic time the sample arrived; 0 = never
  double insertion_m = 0.0;
  double rotation_rad = 0.0;
  double insertion_rate_m_per_s = 0.0;
  double rotation_rate_rad_per_s = 0.0;
};

enum ForceFlags : int32_t {
  kFlagClamped = 1,
  kFlagFaded = 2,
  kFlagStale = 4,
  kFlagFault = 8,
  kFlagRamping = 16,
  kFlagDamped = 32,  // the passivity controller added damping this tick
};

struct ForceOutput {
  double axial_force_n = 0.0;
  double torque_nm = 0.0;
  // the local model's rise of that force with feed and twist, for a device that renders a spring
  // between commands (K and Kt times the ramp's gain); 0 without a local model, while fading, in a
  // fault, and on an axis whose force was clamped
  double axial_stiffness_n_per_m = 0.0;
  double torsional_stiffness_nm_per_rad = 0.0;
  int32_t flags = 0;
};

class ForceEvaluator {
 public:
  // throws std::invalid_argument naming the field when params are non-finite or out of range
  explicit ForceEvaluator(const HapticParams& params);

  // a new model arrived (models carry made_utime on the same monotonic clock as now_us)
  void set_model(const physics::LocalForceModel& model, int64_t now_us);
  ForceOutput tick(const InstrumentSample& sample, int64_t now_us);

  int64_t faults() const { return faults_; }
  const HapticParams& params() const { return params_; }
  const PassivityController& axial_passivity() const { return axial_pc_; }

 private:
  struct Raw {
    double force_n, torque_nm;
  };
  static Raw evaluate(const physics::LocalForceModel& m, const InstrumentSample& s);
  Raw interpolate(const InstrumentSample& s, int64_t now_us) const;
  bool model_stale(int64_t now_us) const;

  HapticParams params_;
  physics::LocalForceModel model_{}, previous_model_{};
  int64_t model_arrived_us_ = 0;
  bool has_model_ = false, has_previous_ = false;
  PassivityController axial_pc_, torque_pc_;

  double gain_ = 0.0;  // fade/ramp gain in [0, 1]
  bool ramping_in_ = true;
  double last_force_n_ = 0.0, last_torque_nm_ = 0.0;
  int64_t last_tick_us_ = 0;
  int64_t faults_ = 0;
};

}  // namespace pcisim::haptics
