#pragma once
// Reads what an HTTP request target carries: its path and its query parameters.
#include <optional>
#include <string>
#include <string_view>

namespace pcisim::remote {

std::string_view target_path(std::string_view target);
// the value of `key` in the query (no percent-decoding: tokens and numbers need none)
std::optional<std::string> query_param(std::string_view target, std::string_view key);
// the token of an "Authorization: Bearer TOKEN" header, "" when there is none
std::string bearer_token(std::string_view authorization);

}  // namespace pcisim::remote
