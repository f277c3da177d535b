#pragma once
// A whole file as a string (logs, JSON, bytes to compare), for tests; "" when it cannot be read.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace pcisim::test {

inline std::string file_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace pcisim::test
