#pragma once
// The server: owns the threads (haptic 1 kHz, physics at the scene rate, LCM I/O) and wires the
// scene's effects, haptics and protocol together.
#include <atomic>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>

#include "server/scene/scene.h"
#include "server/stats.h"

namespace pcisim::server {

class Server {
 public:
  // builds the scene's world (may take seconds) before any thread starts
  Server(const Scene& scene, lcm::LCM& control);
  ~Server();

  // runs until duration_s elapses (0 = no limit) or *stop becomes true; on the way out it stops
  // the loops and publishes a zero force command. Returns the final figures.
  StatsReport run(double duration_s, const std::atomic<bool>& stop);

  // names of the vessel branches, for wire_state_t (index -> name, "" when unknown)
  std::function<std::string(int)> branch_namer;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pcisim::server
