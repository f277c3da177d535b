#pragma once
// Parameter checks shared by the physics components: each component validates its own params
// (errors name the field, "blood_flow.cell_spacing_m: expected ..."), and World calls the same.
#include <cmath>
#include <stdexcept>
#include <string>

namespace pcisim::physics {

inline void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

// finite and within [lo, hi]
inline bool in(double x, double lo, double hi) { return std::isfinite(x) && x >= lo && x <= hi; }

}  // namespace pcisim::physics
