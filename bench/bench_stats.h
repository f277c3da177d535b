#pragma once
// The statistics every benchmark report uses: the project's one percentile (nearest rank).
#include "realtime/percentile.h"

namespace pcisim::bench {

using realtime::percentile;

}  // namespace pcisim::bench
