#pragma once
// Rejects instrument samples the wire must never see (NaN, Inf, absurd magnitudes): the last
// good sample is kept and the rejection counted.
#include <cstdint>

#include "physics/instrument_input.h"

namespace pcisim::physics {

class InputGuard {
 public:
  const InstrumentInput& accept(const InstrumentInput& in);
  int64_t rejected() const { return rejected_; }

 private:
  InstrumentInput last_;
  int64_t rejected_ = 0;
};

}  // namespace pcisim::physics
