// libFuzzer: an instrument box's profile (clients/bridge/device_profile) and its force shaping.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "clients/bridge/device_profile.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const auto p =
        pcisim::clients::parse_device_profile(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json");
    pcisim::clients::ForceShaper shaper(p.force);
    for (int i = 0; i < 4; ++i) {
      const auto out = shaper.step({1e3, -1e3}, 1e-3, false);
      // whatever the profile, the set-point stays within its limits
      if (!(std::abs(out.axial_n) <= p.force.max_axial_n) || !(std::abs(out.torque_nmm) <= p.force.max_torque_nmm))
        std::abort();
    }
  } catch (const std::exception&) {}
  return 0;
}
