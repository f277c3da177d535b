#include "server/beat_samples.h"

namespace pcisim::server {

xray::BeatSamples beat_samples_mm(const physics::BeatCycle& cycle) {
  xray::BeatSamples s;
  const Eigen::Index n = cycle.rest_m.cols();
  s.rest_mm.reserve(n);
  for (Eigen::Index i = 0; i < n; ++i) s.rest_mm.push_back(1000.0 * cycle.rest_m.col(i));
  for (const Eigen::Matrix3Xd& bin : cycle.at_bin_m) {
    s.at_bin_mm.emplace_back();
    s.at_bin_mm.back().reserve(n);
    for (Eigen::Index i = 0; i < bin.cols(); ++i) s.at_bin_mm.back().push_back(1000.0 * bin.col(i));
  }
  return s;
}

}  // namespace pcisim::server
