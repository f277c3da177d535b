#include "tests/common/fixture_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <system_error>

namespace pcisim::test {
namespace {

namespace fs = std::filesystem;

std::string hex(uint64_t v) {
  char s[32];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(v));
  return s;
}

// PCISIM_BINARY_DIR/test-fixtures/<executable>/<build>/; a new build removes the older ones
fs::path fixture_folder() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const fs::path mine = fs::path(PCISIM_BINARY_DIR) / "test-fixtures" / (ec ? "unknown" : exe.filename().string());
  const fs::path folder = mine / hex(executable_build_key());
  if (!fs::exists(folder, ec)) {
    for (const auto& e : fs::directory_iterator(mine, ec))
      if (e.path() != folder) fs::remove_all(e.path(), ec);
    fs::create_directories(folder, ec);
  }
  return folder;
}

// an exclusive flock on a file beside the fixture, released when it goes out of scope
class FileLock {
 public:
  explicit FileLock(const fs::path& path) : fd_(::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644)) {
    if (fd_ >= 0)
      while (::flock(fd_, LOCK_EX) != 0 && errno == EINTR) {}
  }
  ~FileLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_;
};

}  // namespace

uint64_t executable_build_key() {
  struct stat st {};
  FixtureKey key;
  if (::stat("/proc/self/exe", &st) == 0) {
    key.add(st.st_size);
    key.add(st.st_mtim);
  }
  return key.h;
}

std::string fixture_path(const std::string& name) {
  return (fixture_folder() / name).string();
}

std::string shared_fixture_file(const std::string& name, const std::function<void(const std::string& path)>& make) {
  const fs::path path = fixture_folder() / name;
  std::error_code ec;
  if (fs::is_regular_file(path, ec)) return path.string();
  const FileLock lock(path.string() + ".lock");
  if (fs::is_regular_file(path, ec)) return path.string();  // made while this process waited
  const fs::path tmp = path.string() + ".part" + std::to_string(::getpid());
  try {
    make(tmp.string());
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, path);
  return path.string();
}

}  // namespace pcisim::test
