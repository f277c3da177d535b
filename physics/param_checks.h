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
inline bool in(double x, double lo, double hi) {
  return std::isfinite(x) && x >= lo && x <= hi;
}

// a parameter's allowed range, defined once beside its params struct: the component validates
// with it and the scene loader reads with it, so the two cannot disagree
struct ParamRange {
  double min, max;
  // (a part in 1e12 of slack: a bound given in mm and converted to m must still pass)
  bool contains(double x) const { return in(x, min - 1e-12 * std::abs(min), max + 1e-12 * std::abs(max)); }
  // "[min, max]", shortest form ("[0, 90]")
  std::string describe() const;
};

}  // namespace pcisim::physics
