#pragma once
// Names a file gives for other files inside a folder it is not trusted to leave (a case folder's
// members; the data file a volume header in a case names): relative, no "..", no control
// characters, and still inside the folder once every symbolic link is followed (a link may point
// anywhere, so the resolved path is compared with the folder's, component by component).
#include <string>
#include <string_view>

namespace pcisim::anatomy {

enum class FolderEscape {
  kNone,              // inside: `resolved` is the path with every link followed
  kControlCharacter,  // a NUL or other control character (a name cut at its NUL reads another file)
  kNotRelative,       // empty, absolute, or a ".." component
  kThroughLink,       // a symbolic link leads out of the folder
  kUnresolvable,      // the folder or a link on the way cannot be resolved (a loop, no permission)
};

struct InsideFolder {
  FolderEscape escape = FolderEscape::kNone;
  std::string resolved;  // kNone: the path to open (links followed); else empty
  std::string why;       // not kNone: what is wrong, to follow the quoted name in a message
};

// where `name`, relative to `folder`, leads. A name that does not exist (yet) is inside when its
// existing part is: opening it then says it is missing. The folder itself counts as inside.
InsideFolder resolve_inside_folder(const std::string& folder, const std::string& name);

// the name for messages: control characters as \u00XX (JSON's spelling), the rest as it is
std::string escaped_name(std::string_view name);

}  // namespace pcisim::anatomy
