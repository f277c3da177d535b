#pragma once
// The physics thread: a fixed step at the scene's rate. Each step reads the newest instrument
// sample, steps the world (only the scene's effects), publishes a snapshot and a fresh local
// force model. An overrun is counted and the loop skips ahead instead of bursting to catch up.
#include <atomic>
#include <memory>
#include <thread>
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
  // starts at once; a reset rebuilds it around the same case on a builder thread while this
  // world keeps stepping, and swaps it in between two steps (issue #36: a reset stalled physics
  // for 0.7-1.6 s); the rebuilt world takes this one's contact field instead of building it again
  PhysicsLoop(const Scene& scene, std::shared_ptr<const anatomy::Case> anatomy, SharedState& state);
  ~PhysicsLoop();  // waits for a build in flight
  void run();      // until state.stop

  const std::vector<std::unique_ptr<EffectStats>>& effects() const { return effects_; }
  double rate_hz() const { return rate_hz_; }
  const physics::World& world() const { return *world_; }  // read before run() starts

 private:
  void step_once(int64_t now_ns);
  void publish_model(int64_t now_ns);
  std::unique_ptr<physics::World> make_world() const;
  // the reset's builder: started on a request, swapped in once built (or its error logged and
  // the running world kept)
  void start_build();
  void swap_if_built();

  physics::WorldSpec spec_;
  std::shared_ptr<const anatomy::Case> case_;
  SharedState& state_;
  double rate_hz_;
  std::shared_ptr<const physics::LumenQuery> lumen_cache_;  // the first world's contact field
  std::unique_ptr<physics::World> world_;
  std::thread builder_;
  std::atomic<bool> built_{false};
  std::unique_ptr<physics::World> next_;     // the builder's, read after built_
  std::unique_ptr<physics::World> retired_;  // the world a swap replaced: freed by the next builder
  std::string build_error_;
  std::vector<std::unique_ptr<EffectStats>> effects_;
  InstrumentSlot instrument_;
};

}  // namespace pcisim::server
