#pragma once
// One line naming the machine a benchmark ran on: CPU model, cores, date.
#include <string>

namespace pcisim::bench {

std::string machine_info();

}  // namespace pcisim::bench
