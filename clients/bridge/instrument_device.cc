#include "clients/bridge/instrument_device.h"

#include <fmt/format.h>

namespace pcisim::clients {

std::string ScriptedDevice::describe() const {
  return fmt::format("scripted trainee '{}' ({:.1f} s)", script_.name(), script_.duration_s());
}

}  // namespace pcisim::clients
