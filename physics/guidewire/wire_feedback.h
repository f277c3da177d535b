#pragma once
// The haptic force of the wire (eqs 19-20) and its linearisation into the local force model the
// 1 kHz haptic loop evaluates between physics steps.
#include "physics/guidewire/chain_mail_wire.h"
#include "physics/guidewire/coulomb_friction.h"
#include "physics/guidewire/wall_contact.h"
#include "physics/instrument_input.h"
#include "physics/local_force_model.h"

namespace pcisim::physics {

struct WireFeedback {
  double friction_n = 0.0;  // F_friction along insertion (positive resists insertion)
  double internal_n = 0.0;  // F_internal of eq 19 as the params choose (refused feed or eq 20)
  // both variants, whichever is used (the chain-mail; zero for the rod)
  double internal_refused_feed_n = 0.0;
  double internal_eq20_n = 0.0;
  double stiffness_n_per_m = 0.0;
  double torque_nm = 0.0;  // magnitude of the wall friction torque against turning
  // the wire's elastic torque back on the hub (rod model), signed: positive resists positive
  // rotation whichever way the hand turns, unlike friction
  double elastic_torque_nm = 0.0;
  double torsion_stiffness_nm_per_rad = 0.0;
};

// contact and friction may be null when the scene does not list them
WireFeedback compute_feedback(const ChainMailWire& wire, const GuidewireParams& params, const WallContact* contact,
                              const CoulombFriction* friction);

// linearised at the instrument sample the step used
LocalForceModel to_local_force_model(const WireFeedback& f, const InstrumentInput& at, const GuidewireParams& params,
                                     double time_s, double step_s);

}  // namespace pcisim::physics
