#pragma once
// pcisim-bench subcommands register themselves here: one file per benchmark, each with
//   static const bool registered = pcisim::bench::add("name", "one-line help", run);
// so adding a benchmark touches no shared file.
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace pcisim::bench {

// argv after the subcommand name; returns the process exit code
using BenchMain = std::function<int(const std::vector<std::string>& args)>;

struct BenchEntry {
  std::string help;
  BenchMain run;
};

inline std::map<std::string, BenchEntry>& registry() {
  static std::map<std::string, BenchEntry> entries;
  return entries;
}

inline bool add(const std::string& name, const std::string& help, BenchMain run) {
  registry()[name] = {help, std::move(run)};
  return true;
}

}  // namespace pcisim::bench
