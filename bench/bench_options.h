#pragma once
// The options every sweep takes, parsed once: --quick, --no-plot, --out DIR, --help.
#include <cstdio>
#include <string>
#include <vector>

namespace pcisim::bench {

struct BenchOptions {
  bool quick = false;
  bool plot = true;                       // benchmarks without a plot ignore it
  std::string out_dir = "docs/benchmarks";
};

// -1: go on; otherwise the exit code (0 after --help, 2 for an unknown option, with the usage)
inline int parse_bench_options(const std::vector<std::string>& args, const char* name, const char* usage,
                               BenchOptions* o) {
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--quick") {
      o->quick = true;
    } else if (args[i] == "--no-plot") {
      o->plot = false;
    } else if (args[i] == "--out" && i + 1 < args.size()) {
      o->out_dir = args[++i];
    } else if (args[i] == "--help" || args[i] == "-h") {
      std::printf("%s", usage);
      return 0;
    } else {
      std::fprintf(stderr, "pcisim-bench %s: unknown option '%s'\n%s", name, args[i].c_str(), usage);
      return 2;
    }
  }
  return -1;
}

}  // namespace pcisim::bench
