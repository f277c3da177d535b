#pragma once
// Contacts inside the PBD step (soft-tissue paper Algorithm 1 lines 6-15): a body that collides
// with other shapes hands PbdSystem::step one of these; the step calls it at the places the
// algorithm names. It edits the particles' x and x* directly and must allocate nothing.
#include "physics/pbd/particles.h"

namespace pcisim::physics::pbd {

class ContactProjector {
 public:
  virtual ~ContactProjector() = default;
  // after prediction (lines 6-15): find the contacts, then the stabilisation passes, which move
  // x and x* together and so add no velocity. fraction_of_step: where this substep ends, (0, 1]
  virtual void begin_substep(Particles& particles, double h_s, double fraction_of_step) = 0;
  // one pass over the contacts, after every solver iteration's constraint groups (lines 16-22)
  virtual void project(Particles& particles, double h_s) = 0;
  // after the last iteration, before velocities are updated (line 23)
  virtual void end_substep(const Particles& particles, double h_s) = 0;
};

}  // namespace pcisim::physics::pbd
