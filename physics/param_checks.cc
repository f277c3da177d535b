#include "physics/param_checks.h"

#include <fmt/format.h>

namespace pcisim::physics {

std::string ParamRange::describe() const {
  return fmt::format("[{}, {}]", min, max);
}

}  // namespace pcisim::physics
