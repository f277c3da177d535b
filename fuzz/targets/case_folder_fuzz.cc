// libFuzzer: a whole case folder (anatomy/case/case_folder: read_case), all its files together:
// case.json, vessels.json, the CT header and its detached data, organ.ply, fiducials.json, ...,
// and symbolic links and FIFOs among them. A refusal (CaseError naming the file and the field) is
// the expected answer; anything else (another exception, a crash, a hang on a FIFO or a device, UB,
// a huge allocation, a leak) is a finding.
//
// The fuzzer's bytes are a small archive of the folder's entries, each one
//   %%% NAME\n<content>
// An entry starts with "%%% " at the input's start or just after a newline; NAME runs to the end of
// that line; the content runs to the newline before the next entry (that newline is not content) or
// to the end of the input. Bytes before the first entry are ignored. NAME is [A-Za-z0-9._-]+ with at
// most one "/" (a subfolder), at most 64 characters, not "." or ".."; other entries are skipped, as
// are entries past the 16th. Two special forms take no content:
//   %%% NAME -> TARGET   a symbolic link NAME to TARGET (any text: "/etc/passwd", "../x", "/dev/zero")
//   %%% NAME |fifo       a FIFO named NAME (a reader that opened it blocking would hang)
// The entries are written into a fresh folder (a temporary folder's "case/") and the folder read.
//
// Seeds (fuzz/corpus/case_folder/): a written phantom case and a written kidney case, shrunk to a few
// voxels, a coarse surface and a thinned tree so each is a few KB (the run's -max_len is 64 KB);
// the phantom again with its CT as a MetaImage with detached data, with its vessels through a link
// into a subfolder (all four read), and with a data file outside, a FIFO and a link to /dev/zero
// (refused). Made by the anatomy test that checks they read back:
//   PCISIM_WRITE_CASE_FUZZ_SEEDS=fuzz/corpus/case_folder build/tests/pcisim_anatomy_tests \
//     --gtest_filter=CaseFolderFuzzSeeds.*
// PCISIM_CASE_FUZZ_LOG=1 makes this target say why each input was refused ("read" when it reads):
//   PCISIM_CASE_FUZZ_LOG=1 build-fuzz/fuzz/fuzz_case_folder -runs=0 fuzz/corpus/case_folder
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "anatomy/case/case_folder.h"

namespace {

namespace fs = std::filesystem;

constexpr size_t kMaxEntries = 16;       // more files than any case has
constexpr size_t kMaxNameChars = 64;     // case files have short names
constexpr size_t kMaxTargetChars = 256;  // a link's target: any path

// the temporary folder, made once per process and removed at exit
struct Scratch {
  fs::path root;
  Scratch() {
    std::string tmpl = (fs::temp_directory_path() / "pcisim-case-fuzz-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) std::abort();
    root = tmpl;
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(root, ec);
  }
};

const fs::path& scratch() {
  static const Scratch s;
  return s.root;
}

bool valid_name(std::string_view name) {
  if (name.empty() || name.size() > kMaxNameChars) return false;
  int slashes = 0;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                    c == '_' || c == '-' || c == '/';
    if (!ok) return false;
    slashes += c == '/';
  }
  if (slashes > 1 || name.front() == '/' || name.back() == '/') return false;
  for (const std::string_view part : {name.substr(0, name.find('/')), name.substr(name.find('/') + 1)})
    if (part == "." || part == "..") return false;
  return true;
}

// nothing is ever written through a link (entries "x -> /etc" then "x/passwd" would write
// outside): a name already present, or under a subfolder that is not a real folder, is skipped
bool free_slot(const fs::path& dir, std::string_view name) {
  std::error_code ec;
  const fs::path p = dir / name;
  if (fs::symlink_status(p, ec).type() != fs::file_type::not_found) return false;
  const fs::file_type parent = fs::symlink_status(p.parent_path(), ec).type();
  return parent == fs::file_type::not_found || parent == fs::file_type::directory;
}

// one entry into `dir`; a name or target that does not fit is skipped
void write_entry(const fs::path& dir, std::string_view head, std::string_view content) {
  std::error_code ec;
  if (const size_t arrow = head.find(" -> "); arrow != std::string_view::npos) {
    const std::string_view name = head.substr(0, arrow), target = head.substr(arrow + 4);
    if (!valid_name(name) || !free_slot(dir, name) || target.empty() || target.size() > kMaxTargetChars ||
        target.find('\0') != std::string_view::npos)
      return;
    fs::create_directories((dir / name).parent_path(), ec);
    fs::create_symlink(std::string(target), dir / name, ec);
    return;
  }
  if (head.size() > 6 && head.substr(head.size() - 6) == " |fifo") {
    const std::string_view name = head.substr(0, head.size() - 6);
    if (!valid_name(name) || !free_slot(dir, name)) return;
    fs::create_directories((dir / name).parent_path(), ec);
    ::mkfifo((dir / name).c_str(), 0600);
    return;
  }
  if (!valid_name(head) || !free_slot(dir, head)) return;
  fs::create_directories((dir / head).parent_path(), ec);
  std::ofstream out(dir / head, std::ios::binary);
  out.write(content.data(), static_cast<std::streamsize>(content.size()));
}

void unpack(std::string_view bytes, const fs::path& dir) {
  constexpr std::string_view kMark = "%%% ";
  // the first entry at or after `from`: "%%% " at the start or after a newline
  auto entry_at_or_after = [&](size_t from) -> size_t {
    if (from == 0 && bytes.starts_with(kMark)) return 0;
    const size_t nl = bytes.find("\n%%% ", from == 0 ? 0 : from - 1);
    return nl == std::string_view::npos ? nl : nl + 1;
  };
  size_t start = entry_at_or_after(0);
  for (size_t n = 0; start != std::string_view::npos && n < kMaxEntries; ++n) {
    const size_t head_start = start + kMark.size();
    const size_t eol = std::min(bytes.find('\n', head_start), bytes.size());
    const std::string_view head = bytes.substr(head_start, eol - head_start);
    const size_t content_start = std::min(eol + 1, bytes.size());
    const size_t next = entry_at_or_after(content_start);
    // the content ends at the newline before the next entry (none when that entry follows at once)
    const size_t content_end = next == std::string_view::npos ? bytes.size() : std::max(next - 1, content_start);
    write_entry(dir, head, bytes.substr(content_start, content_end - content_start));
    start = next;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // PCISIM_CASE_FUZZ_LOG=1: say whether each input read, and why not (to check the seeds)
  static const bool log = std::getenv("PCISIM_CASE_FUZZ_LOG") != nullptr;
  const fs::path dir = scratch() / "case";
  std::error_code ec;
  fs::remove_all(dir, ec);  // links are removed, never followed
  fs::create_directories(dir, ec);
  if (ec) return 0;
  unpack(std::string_view(reinterpret_cast<const char*>(data), size), dir);
  try {
    (void)pcisim::anatomy::read_case(dir.string());
    if (log) std::fprintf(stderr, "read\n");
  } catch (const pcisim::anatomy::CaseError& e) {
    if (log) std::fprintf(stderr, "refused: %s\n", e.what());
  }
  return 0;
}
