#include "physics/guidewire/input_guard.h"

#include <cmath>

namespace pcisim::physics {
namespace {

// |x| below 1e6 (a kilometre of wire, a million radians) and finite
bool sane(double x) {
  return std::isfinite(x) && std::abs(x) < 1e6;
}

}  // namespace

const InstrumentInput& InputGuard::accept(const InstrumentInput& in) {
  if (sane(in.insertion_m) && sane(in.rotation_rad) && sane(in.insertion_rate_m_per_s) &&
      sane(in.rotation_rate_rad_per_s)) {
    last_ = in;
  } else {
    ++rejected_;
  }
  return last_;
}

}  // namespace pcisim::physics
