#include "json/json_reader.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <vector>

namespace pcisim::json {

std::string short_dump(const nlohmann::json& value) {
  // dump() recurses, but values reach here only from parse_json_checked (depth <= 64)
  std::string s = value.dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

nlohmann::json parse_json_checked(const std::string& text, const std::string& source) {
  // the JSON path as the parser walks: one entry per open object or array, the key or "[]"
  struct Level {
    bool object = false;
    std::string key;
    std::vector<std::string> keys;  // seen in this object
  };
  std::vector<Level> levels;
  auto path = [&] {
    std::string p;
    for (const auto& l : levels) {
      if (!l.object) {
        p += "[]";
      } else if (!l.key.empty()) {
        p += (p.empty() ? "" : ".") + l.key;
      }
    }
    return p.empty() ? source : source + ": " + p;
  };
  using E = nlohmann::json::parse_event_t;
  const nlohmann::json::parser_callback_t cb = [&](int depth, E event, nlohmann::json& parsed) {
    switch (event) {
      case E::object_start:
      case E::array_start:
        if (depth >= kMaxJsonDepth)
          throw JsonError(fmt::format("{}: nested deeper than {} levels", path(), kMaxJsonDepth));
        levels.push_back({event == E::object_start, {}, {}});
        break;
      case E::object_end:
      case E::array_end:
        if (!levels.empty()) levels.pop_back();
        break;
      case E::key: {
        Level& l = levels.back();
        const std::string key = parsed.get<std::string>();
        if (std::find(l.keys.begin(), l.keys.end(), key) != l.keys.end()) {
          l.key = key;
          throw JsonError(fmt::format("{}: the key appears twice in one object", path()));
        }
        l.keys.push_back(key);
        l.key = key;
        break;
      }
      case E::value:
        break;
    }
    return true;
  };
  try {
    return nlohmann::json::parse(text, cb, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::exception& e) {  // syntax, a number out of range (1e400), ...
    throw JsonError(fmt::format("{}: not valid JSON: {}", path(), e.what()));
  }
}

const nlohmann::json JsonReader::kEmpty = nlohmann::json::object();
const nlohmann::json JsonReader::kEmptyList = nlohmann::json::array();

JsonReader::JsonReader(const nlohmann::json& object, std::string path) : object_(object), path_(std::move(path)) {
  if (!object_.is_object())
    throw JsonError(fmt::format("{}: expected an object", path_.empty() ? "(top level)" : path_));
}

std::string JsonReader::path_of(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void JsonReader::fail(const std::string& key, const std::string& expected) const {
  throw JsonError(fmt::format("{}: {}", path_of(key), expected));
}

bool JsonReader::has(const std::string& key) const {
  return object_.contains(key);
}

double JsonReader::number(const std::string& key, double fallback, double min, double max) {
  read_.insert(key);
  if (!has(key)) return fallback;
  const auto& v = object_.at(key);
  if (!v.is_number()) fail(key, fmt::format("expected a number in [{}, {}], got {}", min, max, short_dump(v)));
  const double x = v.get<double>();
  if (!std::isfinite(x) || x < min || x > max)
    fail(key, fmt::format("expected a number in [{}, {}], got {}", min, max, short_dump(v)));
  return x;
}

int JsonReader::integer(const std::string& key, int fallback, int min, int max) {
  read_.insert(key);
  if (!has(key)) return fallback;
  const auto& v = object_.at(key);
  if (!v.is_number_integer() || v.get<int64_t>() < min || v.get<int64_t>() > max)
    fail(key, fmt::format("expected an integer in [{}, {}], got {}", min, max, short_dump(v)));
  return static_cast<int>(v.get<int64_t>());
}

bool JsonReader::boolean(const std::string& key, bool fallback) {
  read_.insert(key);
  if (!has(key)) return fallback;
  const auto& v = object_.at(key);
  if (!v.is_boolean()) fail(key, fmt::format("expected true or false, got {}", short_dump(v)));
  return v.get<bool>();
}

std::string JsonReader::text(const std::string& key, const std::string& fallback,
                             const std::vector<std::string>& allowed) {
  read_.insert(key);
  if (!has(key)) return fallback;
  const auto& v = object_.at(key);
  const bool ok = v.is_string() &&
                  (allowed.empty() || std::find(allowed.begin(), allowed.end(), v.get<std::string>()) != allowed.end());
  if (!ok)
    fail(key, allowed.empty()
                  ? fmt::format("expected a string, got {}", short_dump(v))
                  : fmt::format("expected one of \"{}\", got {}", fmt::join(allowed, "\", \""), short_dump(v)));
  return v.get<std::string>();
}

JsonReader JsonReader::child(const std::string& key) {
  read_.insert(key);
  if (!has(key)) return JsonReader(kEmpty, path_of(key));
  return JsonReader(object_.at(key), path_of(key));
}

const nlohmann::json& JsonReader::list(const std::string& key) {
  read_.insert(key);
  if (!has(key)) return kEmptyList;
  if (!object_.at(key).is_array()) fail(key, fmt::format("expected a list, got {}", short_dump(object_.at(key))));
  return object_.at(key);
}

const nlohmann::json* JsonReader::value(const std::string& key) {
  read_.insert(key);
  return has(key) ? &object_.at(key) : nullptr;
}

bool JsonReader::numbers(const std::string& key, std::span<double> out) {
  const nlohmann::json& v = list(key);
  if (v.size() != out.size()) return false;
  for (size_t i = 0; i < out.size(); ++i) {
    if (!v[i].is_number()) return false;
    out[i] = v[i].get<double>();
    if (!std::isfinite(out[i])) return false;
  }
  return true;
}

void JsonReader::finish() const {
  for (const auto& [key, value] : object_.items()) {
    if (read_.count(key)) continue;
    throw JsonError(fmt::format("{}: unknown key (this object accepts: {})", path_of(key),
                                read_.empty() ? std::string("nothing") : fmt::format("{}", fmt::join(read_, ", "))));
  }
}

}  // namespace pcisim::json
