#include "server/scene/json_reader.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fmt/ranges.h>

namespace pcisim::server {

const nlohmann::json JsonReader::kEmpty = nlohmann::json::object();
const nlohmann::json JsonReader::kEmptyList = nlohmann::json::array();

JsonReader::JsonReader(const nlohmann::json& object, std::string path)
    : object_(object), path_(std::move(path)) {
  if (!object_.is_object()) throw SceneError(fmt::format("{}: expected an object", path_.empty() ? "(top level)" : path_));
}

std::string JsonReader::path_of(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void JsonReader::fail(const std::string& key, const std::string& expected) const {
  throw SceneError(fmt::format("{}: {}", path_of(key), expected));
}

bool JsonReader::has(const std::string& key) const { return object_.contains(key); }

double JsonReader::number(const std::string& key, double fallback, double min, double max) {
  read_.insert(key);
  if (!has(key)) return fallback;
  const auto& v = object_.at(key);
  if (!v.is_number()) fail(key, fmt::format("expected a number in [{}, {}], got {}", min, max, v.dump()));
  const double x = v.get<double>();
  if (!std::isfinite(x) || x < min || x > max)
    fail(key, fmt::format("expected a number in [{}, {}], got {}", min, max, v.dump()));
  return x;
}

int JsonReader::integer(const std::string& key, int fallback, int min, int max) {
  read_.insert(key);
  if (!has(key)) return fallback;
  const auto& v = object_.at(key);
  if (!v.is_number_integer() || v.get<int64_t>() < min || v.get<int64_t>() > max)
    fail(key, fmt::format("expected an integer in [{}, {}], got {}", min, max, v.dump()));
  return static_cast<int>(v.get<int64_t>());
}

bool JsonReader::boolean(const std::string& key, bool fallback) {
  read_.insert(key);
  if (!has(key)) return fallback;
  const auto& v = object_.at(key);
  if (!v.is_boolean()) fail(key, fmt::format("expected true or false, got {}", v.dump()));
  return v.get<bool>();
}

std::string JsonReader::text(const std::string& key, const std::string& fallback,
                             const std::vector<std::string>& allowed) {
  read_.insert(key);
  if (!has(key)) return fallback;
  const auto& v = object_.at(key);
  const bool ok = v.is_string() && (allowed.empty() || std::find(allowed.begin(), allowed.end(), v.get<std::string>()) != allowed.end());
  if (!ok)
    fail(key, allowed.empty() ? fmt::format("expected a string, got {}", v.dump())
                              : fmt::format("expected one of \"{}\", got {}", fmt::join(allowed, "\", \""), v.dump()));
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
  if (!object_.at(key).is_array()) fail(key, fmt::format("expected a list, got {}", object_.at(key).dump()));
  return object_.at(key);
}

void JsonReader::finish() const {
  for (const auto& [key, value] : object_.items()) {
    if (read_.count(key)) continue;
    throw SceneError(fmt::format("{}: unknown key (this object accepts: {})", path_of(key),
                                 read_.empty() ? std::string("nothing") : fmt::format("{}", fmt::join(read_, ", "))));
  }
}

}  // namespace pcisim::server
