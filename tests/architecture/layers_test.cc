// The layers of DESIGN.md, checked on the real tree: every #include of every library source and
// every library target's link list (written by CMake at configure time) must follow an edge the
// design allows. A wrong-way include also fails to compile (each library sees only the include
// roots of what it links); this test names the edge and the file.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// what each layer may include and link, besides itself; a path ending in ".h" allows that header
// only (haptics sees the plain local force model, not physics)
const std::map<std::string, std::vector<std::string>>& allowed() {
  static const std::map<std::string, std::vector<std::string>> rules = {
      {"anatomy", {"json", "png", "realtime/percentile.h"}},
      {"realtime", {}},
      {"json", {}},
      {"png", {}},
      {"physics", {"anatomy"}},
      {"haptics", {"physics/local_force_model.h"}},
      {"xray", {"anatomy", "png", "realtime/percentile.h", "realtime/row_pool.h"}},
      {"ultrasound", {"anatomy", "png", "realtime/percentile.h", "realtime/row_pool.h"}},
      {"modeling", {"anatomy", "json", "png", "realtime/percentile.h", "realtime/stop_signal.h"}},
      {"protocol", {"pcisim_lcm"}},
      {"server",
       {"anatomy", "physics", "haptics", "xray", "ultrasound", "protocol", "pcisim_lcm", "realtime", "json", "png"}},
      {"clients", {"protocol", "pcisim_lcm", "realtime", "json", "anatomy", "png"}},
      // the dataset maker runs scenes headless: the server's scene library, not its threads
      {"dataset",
       {"server/scene/scene.h", "server/case_builder.h", "server/beat_samples.h", "anatomy", "physics", "xray", "json",
        "png", "clients/bridge/trainee_script.h", "realtime/stop_signal.h"}},
  };
  return rules;
}

// the libraries a layer links for the single headers it may include of another layer: the dataset
// maker links the server's scene library (not the server with its threads and LCM) and the
// clients' library for the trainee script reader
const std::map<std::string, std::set<std::string>>& header_libraries() {
  static const std::map<std::string, std::set<std::string>> libs = {
      {"dataset", {"pcisim_scene", "pcisim_clients_lib"}},
      // the one percentile (realtime/percentile.h) for the layers that take quantiles of samples,
      // and the row pool (realtime/row_pool.h) for those that spread a frame over threads
      {"anatomy", {"pcisim_realtime"}},
      {"xray", {"pcisim_realtime"}},
      {"ultrasound", {"pcisim_realtime"}},
      {"modeling", {"pcisim_realtime"}},
  };
  return libs;
}

// wrong-way edges tolerated for now: each entry is a debt to pay, a new one fails the test.
// None today (the "Anatomy as data" issue paid the last: the coronary tree moved to anatomy/, the
// realtime primitives and the JSON reader out of server/).
const std::set<std::pair<std::string, std::string>>& known_debts() {
  static const std::set<std::pair<std::string, std::string>> debts = {};
  return debts;
}

bool edge_allowed(const std::string& layer, const std::string& include) {
  if (known_debts().contains({layer, include})) return true;
  const auto slash = include.find('/');
  const std::string head = include.substr(0, slash);
  if (head == layer) return true;
  for (const auto& a : allowed().at(layer)) {
    if (a.ends_with(".h") ? include == a : head == a) return true;
  }
  return false;
}

struct Violation {
  std::string where, what;
};

// every quoted include naming a top-level folder of the repository (or the generated LCM types)
std::vector<Violation> check_includes(const fs::path& root) {
  static const std::regex include_re(R"(^\s*#\s*include\s*"([^"]+)\")");
  std::set<std::string> top;
  for (const auto& e : fs::directory_iterator(root))
    if (e.is_directory()) top.insert(e.path().filename().string());
  top.insert("pcisim_lcm");
  std::vector<Violation> out;
  for (const auto& [layer, _] : allowed()) {
    if (!fs::exists(root / layer)) continue;
    for (const auto& e : fs::recursive_directory_iterator(root / layer)) {
      const std::string ext = e.path().extension().string();
      if (!e.is_regular_file() || (ext != ".h" && ext != ".cc" && ext != ".cu" && ext != ".cuh" && ext != ".in"))
        continue;
      std::ifstream in(e.path());
      std::string line;
      int n = 0;
      while (std::getline(in, line)) {
        ++n;
        std::smatch m;
        if (!std::regex_search(line, m, include_re)) continue;
        const std::string inc = m[1];
        const auto slash = inc.find('/');
        if (slash == std::string::npos || !top.contains(inc.substr(0, slash))) continue;  // a local or system header
        if (!edge_allowed(layer, inc))
          out.push_back({fs::relative(e.path(), root).string() + ":" + std::to_string(n), layer + " includes " + inc});
      }
    }
  }
  return out;
}

// lines "TARGET LAYER DEP;DEP;..." from CMake; a dep that is a pcisim target must be an allowed layer
std::vector<Violation> check_links(const fs::path& targets_file, int* targets_seen) {
  std::ifstream in(targets_file);
  std::map<std::string, std::string> layer_of;
  std::vector<std::tuple<std::string, std::string, std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string target, layer, deps;
    s >> target >> layer >> deps;
    layer_of[target] = layer;
    rows.emplace_back(target, layer, deps);
  }
  *targets_seen = static_cast<int>(rows.size());
  std::vector<Violation> out;
  for (const auto& [target, layer, deps] : rows) {
    if (!allowed().contains(layer)) continue;  // tests, bench, fuzz and programs may link anything
    std::istringstream s(deps);
    std::string dep;
    while (std::getline(s, dep, ';')) {
      const auto it = layer_of.find(dep);
      if (it == layer_of.end()) continue;  // a third-party library
      // a target whose layer is one header (the local force model) is an edge to that header
      const std::string edge = it->second.ends_with(".h") ? it->second : it->second + "/";
      // a layer allowed some headers of another links the one library that holds them
      const auto lib = header_libraries().find(layer);
      const bool via_header = lib != header_libraries().end() && lib->second.contains(dep);
      if (!via_header && !edge_allowed(layer, edge))
        out.push_back({target, layer + " links " + dep + " (" + it->second + ")"});
    }
  }
  return out;
}

std::string describe(const std::vector<Violation>& v) {
  std::string s;
  for (const auto& x : v) s += "  " + x.where + ": " + x.what + "\n";
  return s;
}

TEST(Layers, EveryIncludeFollowsAnAllowedEdge) {
  const auto v = check_includes(PCISIM_SOURCE_DIR);
  EXPECT_TRUE(v.empty()) << "wrong-way includes (DESIGN.md, dependency direction):\n" << describe(v);
}

TEST(Layers, EveryLibraryLinksOnlyAllowedLayers) {
  int seen = 0;
  const auto v = check_links(fs::path(PCISIM_BINARY_DIR) / "architecture" / "targets.txt", &seen);
  EXPECT_GT(seen, 5) << "CMake wrote no target list";
  EXPECT_TRUE(v.empty()) << "wrong-way links:\n" << describe(v);
}

// the checker itself finds what it must: a physics file including the server, haptics reaching
// past the local force model, a client including server/
TEST(Layers, CheckerFindsWrongWayIncludesInATree) {
  const fs::path root = fs::temp_directory_path() / ("pcisim-layers-" + std::to_string(::getpid()));
  fs::remove_all(root);
  for (const char* d : {"physics", "haptics", "server", "clients", "anatomy"}) fs::create_directories(root / d);
  std::ofstream(root / "physics/a.cc") << "#include \"anatomy/x.h\"\n#include \"server/server.h\"\n";
  std::ofstream(root / "haptics/b.h") << "#include \"physics/local_force_model.h\"\n#include \"physics/world.h\"\n";
  std::ofstream(root / "clients/c.cc") << "#include <vector>\n  #  include \"server/server.h\"\n#include \"c.h\"\n";
  const auto v = check_includes(root);
  fs::remove_all(root);
  ASSERT_EQ(v.size(), 3u) << describe(v);
  EXPECT_EQ(v[0].where, "clients/c.cc:2");
  EXPECT_EQ(v[1].what, "haptics includes physics/world.h");
  EXPECT_EQ(v[2].what, "physics includes server/server.h");
}

}  // namespace
