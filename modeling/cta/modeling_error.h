#pragma once
// What the modeling pipeline throws when it cannot make a model of the images it was given: the
// message names the input at fault and the numbers found (a seed and the HU there, a volume's size
// against the memory bound), so a person can act on it.
#include <stdexcept>

namespace pcisim::modeling {

struct ModelingError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace pcisim::modeling
