#include "json/regular_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace pcisim::json {
namespace {

// closes its descriptor however the reader leaves (an allocation that throws included)
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

// what a stat mode is, for "not a regular file" messages
const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a plain file";
}

// opened without blocking (a FIFO's open would wait for a writer), then checked on the open file,
// so nothing can be swapped in between the check and the read; -1 with *why set on refusal
int open_regular(const std::string& path, const std::string& what, struct stat* st, std::string* why) {
  if (path.find('\0') != std::string::npos) {
    *why = fmt::format("{}\\0...: a NUL character in the path of {}", path.substr(0, path.find('\0')), what);
    return -1;
  }
  if (path.empty()) {
    *why = fmt::format("an empty path for {}", what);
    return -1;
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    const int e = errno;
    *why = fmt::format("{}: cannot open {}: {}", path, what, std::strerror(e));
    return -1;
  }
  if (::fstat(fd, st) != 0 || !S_ISREG(st->st_mode)) {
    ::close(fd);  // before the message, whose formatting may throw
    *why = fmt::format("{}: not a regular file ({}, never read as {})", path, kind_of(st->st_mode), what);
    return -1;
  }
  return fd;
}

// at most n bytes from fd's current offset (fewer where the file ends first)
std::string read_up_to(int fd, int64_t n, const std::string& path, const std::string& what) {
  std::string out(static_cast<size_t>(n), '\0');
  size_t got = 0;
  while (got < out.size()) {
    const ssize_t r = ::read(fd, out.data() + got, out.size() - got);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) throw FileError(fmt::format("{}: cannot read {}: {}", path, what, std::strerror(errno)));
    if (r == 0) break;
    got += static_cast<size_t>(r);
  }
  out.resize(got);
  return out;
}

}  // namespace

std::string read_regular_file(const std::string& path, const std::string& what, int64_t max_bytes) {
  struct stat st {};
  std::string why;
  const Fd file{open_regular(path, what, &st, &why)};
  if (file.fd < 0) throw FileError(why);
  if (st.st_size > max_bytes)
    throw FileError(fmt::format("{}: {} bytes, over the {} byte limit for {}", path, st.st_size, max_bytes, what));
  std::string out = read_up_to(file.fd, st.st_size, path, what);
  if (static_cast<int64_t>(out.size()) != st.st_size)
    throw FileError(fmt::format("{}: {} shrank while it was read", path, what));
  return out;
}

std::string read_regular_file_head(const std::string& path, const std::string& what, int64_t bytes) {
  struct stat st {};
  std::string why;
  const Fd file{open_regular(path, what, &st, &why)};
  if (file.fd < 0) throw FileError(why);
  return read_up_to(file.fd, std::min<int64_t>(bytes, st.st_size), path, what);
}

std::string regular_file_problem(const std::string& path, const std::string& what) {
  struct stat st {};
  std::string why;
  const int fd = open_regular(path, what, &st, &why);
  if (fd >= 0) ::close(fd);
  return why;
}

}  // namespace pcisim::json
