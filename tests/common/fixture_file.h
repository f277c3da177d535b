#pragma once
// A file that an expensive test set-up makes once and the test processes of one test executable
// share (CTest runs each test in a process of its own, so a cache in memory is not shared).
// Kept in PCISIM_BINARY_DIR/test-fixtures/<executable>/<build>/, where <build> is the
// executable's size and time: a rebuilt executable never reads what an older build made, and
// its first use removes the older builds' files.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

namespace pcisim::test {

// the path of the fixture `name` (a file name), made by make(path) if no process of this build
// has made it yet. The first process to ask makes it under a lock while the others wait, then
// read it; make() writes into a temporary path that is renamed into place once it returns, so a
// reader never sees half a file. make() throwing leaves no file behind (and rethrows).
std::string shared_fixture_file(const std::string& name, const std::function<void(const std::string& path)>& make);

// where the fixture `name` of this build is kept (it may not exist yet)
std::string fixture_path(const std::string& name);

// FNV-1a over raw bytes, for the keys of fixtures (a key, not a digest anyone trusts with security)
struct FixtureKey {
  uint64_t h = 1469598103934665603ull;
  void add(const void* p, size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
  template <class T>
  void add(const T& v) {
    add(&v, sizeof v);
  }
};

// the key of this executable's build (its size and modification time), for keys of fixtures
uint64_t executable_build_key();

}  // namespace pcisim::test
