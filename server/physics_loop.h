#pragma once
// The physics thread: a fixed step at the scene's rate. Each step reads the newest instrument
// sample, steps the world (only the scene's effects), publishes a snapshot and a fresh local
// force model. An overrun is counted and the loop skips ahead instead of bursting to catch up.
#include <memory>
#include <string>
#include <vector>

#include "anatomy/case/case.h"
#include "physics/world.h"
#include "server/scene/scene.h"
#include "server/shared_state.h"

namespace pcisim::server {

struct EffectStats {
  std::string name;
  realtime::LatencyHistogram step_ns;
};

class PhysicsLoop {
 public:
  // builds the world around the scene's case now (may take a while: SDF), so the loop itself
  // starts at once; a reset rebuilds it around the same case
  PhysicsLoop(const Scene& scene, std::shared_ptr<const anatomy::Case> anatomy, SharedState& state);
  void run();  // until state.stop

  const std::vector<std::unique_ptr<EffectStats>>& effects() const { return effects_; }
  double rate_hz() const { return rate_hz_; }
  const physics::World& world() const { return *world_; }  // read before run() starts

 private:
  void step_once(int64_t now_ns);
  std::unique_ptr<physics::World> make_world() const;

  physics::WorldSpec spec_;
  std::shared_ptr<const anatomy::Case> case_;
  SharedState& state_;
  double rate_hz_;
  std::unique_ptr<physics::World> world_;
  std::vector<std::unique_ptr<EffectStats>> effects_;
  InstrumentSlot instrument_;
};

}  // namespace pcisim::server
