#pragma once
// Reads one JSON object (a scene, a case, a trainee script), checking each value's type and range and, at the end, that
// no key was left unread. Every error names the JSON path and what was expected.
#include <nlohmann/json.hpp>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace pcisim::json {

class JsonError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// parses JSON with comments for the readers above: at most kMaxJsonDepth levels of nesting (a
// 100 000-deep file overflowed the stack), no key twice in one object (the last silently won), and
// every error names `source`, the byte and the JSON path reached. Throws JsonError.
inline constexpr int kMaxJsonDepth = 64;
nlohmann::json parse_json_checked(const std::string& text, const std::string& source);

// a value for an error message: its JSON, cut to a line
std::string short_dump(const nlohmann::json& value);

class JsonReader {
 public:
  // `object` must outlive the reader; `path` is its JSON path, e.g. "effects.guidewire"
  JsonReader(const nlohmann::json& object, std::string path);

  double number(const std::string& key, double fallback, double min, double max);
  int integer(const std::string& key, int fallback, int min, int max);
  bool boolean(const std::string& key, bool fallback);
  std::string text(const std::string& key, const std::string& fallback, const std::vector<std::string>& allowed = {});
  bool has(const std::string& key) const;
  JsonReader child(const std::string& key);             // an object; {} when absent
  const nlohmann::json& list(const std::string& key);   // an array; [] when absent
  const nlohmann::json* value(const std::string& key);  // any value, unchecked; null when absent
  // a list of exactly out.size() finite numbers under `key` into `out`; false (out unspecified)
  // otherwise, so the caller names what it expected. Fails like list() when it is not a list
  bool numbers(const std::string& key, std::span<double> out);

  // throws if any key was never read, listing the keys this object accepts
  void finish() const;

  std::string path_of(const std::string& key) const;
  [[noreturn]] void fail(const std::string& key, const std::string& expected) const;

 private:
  const nlohmann::json& object_;
  std::string path_;
  std::set<std::string> read_;
  static const nlohmann::json kEmpty, kEmptyList;
};

}  // namespace pcisim::json
