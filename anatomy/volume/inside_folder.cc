#include "anatomy/volume/inside_folder.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <system_error>

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;

// whether `p` is `folder` or below it, component by component ("/a/bc" is not inside "/a/b")
bool within(const fs::path& folder, const fs::path& p) {
  auto f = folder.begin();
  auto q = p.begin();
  for (; f != folder.end(); ++f, ++q) {
    if (f->empty()) continue;  // a trailing separator's empty element
    if (q == p.end() || *q != *f) return false;
  }
  return true;
}

// what escaped_name shows as \uXXXX and a name may not hold: C0 controls (NUL included) and DEL
bool is_control(char c) {
  const auto u = static_cast<unsigned char>(c);
  return u < 0x20 || u == 0x7f;
}

InsideFolder refuse(FolderEscape e, std::string why) {
  InsideFolder out;
  out.escape = e;
  out.why = std::move(why);
  return out;
}

}  // namespace

std::string escaped_name(std::string_view name) {
  std::string out;
  for (const char c : name) {
    if (is_control(c)) {
      out += fmt::format("\\u{:04x}", static_cast<unsigned char>(c));
    } else {
      out += c;
    }
  }
  return out;
}

InsideFolder resolve_inside_folder(const std::string& folder, const std::string& name) {
  if (std::any_of(name.begin(), name.end(), is_control))
    return refuse(FolderEscape::kControlCharacter, "holds a control character");
  const fs::path rel(name);
  if (name.empty()) return refuse(FolderEscape::kNotRelative, "is empty");
  if (rel.has_root_path()) return refuse(FolderEscape::kNotRelative, "is an absolute path");
  for (const fs::path& part : rel)
    if (part == "..") return refuse(FolderEscape::kNotRelative, "goes up with '..'");
  std::error_code ec;
  const fs::path base = fs::canonical(folder.empty() ? fs::path(".") : fs::path(folder), ec);
  if (ec) return refuse(FolderEscape::kUnresolvable, fmt::format("cannot be resolved: the folder {}", ec.message()));
  // every existing link followed; a missing tail is kept as written
  const fs::path full = fs::weakly_canonical(base / rel, ec);
  if (ec) return refuse(FolderEscape::kUnresolvable, fmt::format("cannot be resolved: {}", ec.message()));
  if (!within(base, full)) {
    // what it leads to, from a stat (never opened: a device's open can act)
    const fs::file_status st = fs::status(full, ec);
    const char* kind = fs::is_character_file(st) ? " (a character device)"
                       : fs::is_block_file(st)   ? " (a block device)"
                       : fs::is_fifo(st)         ? " (a FIFO)"
                       : fs::is_directory(st)    ? " (a folder)"
                                                 : "";
    return refuse(FolderEscape::kThroughLink,
                  fmt::format("leads to '{}'{} through a symbolic link, outside the folder {}",
                              escaped_name(full.string()), kind, base.string()));
  }
  // a link in the missing tail points at nothing yet: opening it would follow it wherever it
  // points, so it is refused too
  for (fs::path p = full; p != base && within(base, p) && p.has_relative_path(); p = p.parent_path()) {
    std::error_code lec;
    if (fs::is_symlink(fs::symlink_status(p, lec))) {
      const fs::path target = fs::read_symlink(p, lec);
      return refuse(FolderEscape::kThroughLink,
                    fmt::format("is a symbolic link to '{}', which does not exist", escaped_name(target.string())));
    }
  }
  InsideFolder out;
  out.resolved = full.string();
  return out;
}

}  // namespace pcisim::anatomy
