#pragma once
// Two random access tokens, one per role. A token is the only credential: whoever holds the
// controller token may steer the session, so tokens come from the kernel's CSPRNG.
#include <optional>
#include <string>
#include <string_view>

namespace pcisim::remote {

enum class Role { kObserver, kController };

const char* role_name(Role role);

class AccessTokens {
 public:
  AccessTokens();  // fresh random tokens
  AccessTokens(std::string observer, std::string controller);

  // the role a presented token grants; nothing for a missing or wrong token
  std::optional<Role> role_of(std::string_view token) const;
  const std::string& observer() const { return observer_; }
  const std::string& controller() const { return controller_; }

  static std::string random_token();  // 128 bits, lowercase hex

 private:
  std::string observer_, controller_;
};

}  // namespace pcisim::remote
