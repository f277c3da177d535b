#include "server/beat_samples.h"

namespace pcisim::server {

xray::BeatSamples beat_samples_mm(const physics::BeatCycle& cycle) {
  return xray::beat_samples_from_m(cycle.rest_m, cycle.at_bin_m);
}

}  // namespace pcisim::server
