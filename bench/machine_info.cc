#include "bench/machine_info.h"

#include <ctime>
#include <fstream>
#include <string>
#include <thread>

namespace pcisim::bench {

std::string machine_info() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(cpuinfo, line))
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d", std::gmtime(&now));
  return model + ", " + std::to_string(std::thread::hardware_concurrency()) + " cores, " + date;
}

}  // namespace pcisim::bench
