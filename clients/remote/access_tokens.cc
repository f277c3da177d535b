#include "clients/remote/access_tokens.h"

#include <stdexcept>
#include <sys/random.h>

namespace pcisim::remote {

const char* role_name(Role role) {
  return role == Role::kController ? "controller" : "observer";
}

AccessTokens::AccessTokens() : observer_(random_token()), controller_(random_token()) {}

AccessTokens::AccessTokens(std::string observer, std::string controller)
    : observer_(std::move(observer)), controller_(std::move(controller)) {
  if (observer_.empty() || controller_.empty() || observer_ == controller_)
    throw std::invalid_argument("access tokens must be non-empty and differ");
}

std::string AccessTokens::random_token() {
  unsigned char bytes[16];
  size_t got = 0;
  while (got < sizeof bytes) {
    const ssize_t n = getrandom(bytes + got, sizeof bytes - got, 0);
    if (n < 0) throw std::runtime_error("getrandom failed: no secure randomness for tokens");
    got += static_cast<size_t>(n);
  }
  static const char* hex = "0123456789abcdef";
  std::string s;
  for (unsigned char b : bytes) {
    s += hex[b >> 4];
    s += hex[b & 15];
  }
  return s;
}

namespace {
// compares in time independent of where the strings differ, so timing leaks no prefix
bool same(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}
}  // namespace

std::optional<Role> AccessTokens::role_of(std::string_view token) const {
  if (token.empty()) return std::nullopt;
  if (same(token, controller_)) return Role::kController;
  if (same(token, observer_)) return Role::kObserver;
  return std::nullopt;
}

}  // namespace pcisim::remote
