// pcisim-bench NAME [options]: measures what accuracy costs in time. Each benchmark sweeps its
// knobs against a reference and writes a report to docs/benchmarks/ (see bench_registry.h).
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_registry.h"

int main(int argc, char** argv) {
  auto& entries = pcisim::bench::registry();
  const std::string name = argc > 1 ? argv[1] : "";
  if (name.empty() || name == "--help" || name == "-h" || !entries.count(name)) {
    if (!name.empty() && name != "--help" && name != "-h")
      std::fprintf(stderr, "pcisim-bench: unknown benchmark '%s'\n\n", name.c_str());
    std::printf("usage: pcisim-bench NAME [options]   (pcisim-bench NAME --help for its options)\n\nbenchmarks:\n");
    for (const auto& [n, e] : entries) std::printf("  %-12s %s\n", n.c_str(), e.help.c_str());
    return name.empty() || name == "--help" || name == "-h" ? 0 : 2;
  }
  return entries.at(name).run(std::vector<std::string>(argv + 2, argv + argc));
}
