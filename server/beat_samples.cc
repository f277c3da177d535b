#include "server/beat_samples.h"

namespace pcisim::server {

xray::BeatSamples beat_samples_mm(const physics::BeatCycle& cycle) {
  return xray::beat_samples_from_m(cycle.rest_m, cycle.at_bin_m);
}

xray::BeatingBackgroundOptions beat_options(const XraySpec& spec) {
  xray::BeatingBackgroundOptions o;
  o.interpolate = spec.heart_phase_blend;
  o.projector = spec.fluoro.projector.trilinear;
  if (spec.fluoro.projector.projector == xray::ProjectorKind::kCudaTrilinear) {
    o.gpu = true;
    o.change_stride = 1;
  }
  return o;
}

}  // namespace pcisim::server
