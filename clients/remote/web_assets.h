#pragma once
// The page, embedded in the binary at build time (web/ through embed_web_assets.cmake), so the
// gateway needs no files and the page no network.
#include <string_view>

namespace pcisim::remote {

struct WebAsset {
  std::string_view path;  // "/", "/app.js", ...
  std::string_view content_type;
  std::string_view body;
};

// nullptr when no asset has that path
const WebAsset* find_web_asset(std::string_view path);

}  // namespace pcisim::remote
