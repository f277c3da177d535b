// libFuzzer: a heart motion file's bytes (anatomy/heart/heart_motion), then a lookup in it.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "anatomy/heart/heart_motion.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const auto m =
        pcisim::anatomy::HeartMotion::parse(std::string(reinterpret_cast<const char*>(data), size), "fuzz.motion");
    (void)m.frame_displacement_m(0, Eigen::Vector3d::Zero());
  } catch (const std::invalid_argument&) {}
  return 0;
}
