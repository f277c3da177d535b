#pragma once
// The one reader of the files a user names (scenes, cases, trainee and probe scripts, dataset
// specs, volumes, meshes): only a regular file of a bounded size is read. A FIFO would block the
// reader for ever and /dev/zero never ends, so both are refused unread (opened without blocking and
// checked on the open file); a size is checked before
// a byte is read. Every error names the path and the cause.
#include <cstdint>
#include <stdexcept>
#include <string>

namespace pcisim::json {

class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// the bytes of the regular file at `path`, at most max_bytes of them. `what` names the file's role
// in messages ("the scene file", "the trainee script"). Throws FileError "<path>: <cause>":
// "cannot open <what>: <the system's reason>", "not a regular file (a FIFO, ...)", "N bytes, over
// the M byte limit for <what>", or "a NUL character in the path" (a name cut at its NUL would
// read another file).
inline constexpr int64_t kMaxRegularFileBytes = int64_t{8} << 30;
std::string read_regular_file(const std::string& path, const std::string& what = "the file",
                              int64_t max_bytes = kMaxRegularFileBytes);

// the first `bytes` bytes of the regular file at `path` (all of it when shorter), whatever its
// size: enough to tell a file's kind from its magic without reading it whole. Throws as above
std::string read_regular_file_head(const std::string& path, const std::string& what, int64_t bytes);

// "" when `path` names a regular file that could be read, else the cause as read_regular_file
// would say it (without reading the file)
std::string regular_file_problem(const std::string& path, const std::string& what = "the file");

}  // namespace pcisim::json
