#pragma once
// The options every sweep takes, parsed once: --quick, --no-plot, --out DIR, --help.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace pcisim::bench {

struct BenchOptions {
  bool quick = false;
  bool plot = true;  // benchmarks without a plot ignore it
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

// runs a plot script with the system python (it has python3-matplotlib; a python3 earlier on PATH,
// pyenv's say, may not): `python script args`. False, with a line saying so, when it fails.
inline bool run_plot_script(const char* bench, const std::string& script_and_args) {
  const std::string python = std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  const std::string cmd = python + " " + script_and_args;
  if (std::system(cmd.c_str()) == 0) return true;
  std::printf("%s: plot skipped (%s failed)\n", bench, cmd.c_str());
  return false;
}

}  // namespace pcisim::bench
