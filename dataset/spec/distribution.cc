#include "dataset/spec/distribution.h"

#include <fmt/format.h>

#include <cmath>

#include "json/json_reader.h"

namespace pcisim::dataset {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& expected) {
  throw json::JsonError(fmt::format("{}: {}", path, expected));
}

// the [a, b] of a range form: two finite numbers, a <= b
void read_range(const nlohmann::json& v, const std::string& path, double* lo, double* hi) {
  if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number())
    fail(path, fmt::format("expected [a, b], two numbers, got {}", json::short_dump(v)));
  *lo = v[0].get<double>();
  *hi = v[1].get<double>();
  if (!std::isfinite(*lo) || !std::isfinite(*hi) || *lo > *hi)
    fail(path, fmt::format("expected finite a <= b, got {}", json::short_dump(v)));
}

}  // namespace

Distribution Distribution::fixed(nlohmann::json value) {
  Distribution d;
  d.kind_ = Kind::kFixed;
  d.values_ = {std::move(value)};
  return d;
}

Distribution Distribution::parse(const nlohmann::json& value, const std::string& path) {
  // an object with one of the four keys is a distribution; anything else is a fixed value
  if (!value.is_object()) return fixed(value);
  if (value.size() != 1)
    fail(path,
         "expected one of {\"uniform\": [a, b]}, {\"log_uniform\": [a, b]}, {\"integers\": [a, b]}, "
         "{\"choice\": [...]} or a plain value");
  Distribution d;
  const std::string key = value.begin().key();
  const nlohmann::json& arg = value.begin().value();
  const std::string sub = path + "." + key;
  if (key == "uniform" || key == "log_uniform" || key == "integers") {
    read_range(arg, sub, &d.lo_, &d.hi_);
    if (key == "uniform") {
      d.kind_ = Kind::kUniform;
    } else if (key == "log_uniform") {
      if (d.lo_ <= 0) fail(sub, fmt::format("expected 0 < a <= b, got {}", json::short_dump(arg)));
      d.kind_ = Kind::kLogUniform;
    } else {
      if (d.lo_ != std::floor(d.lo_) || d.hi_ != std::floor(d.hi_) || std::abs(d.lo_) > 1e15 || std::abs(d.hi_) > 1e15)
        fail(sub, fmt::format("expected two whole numbers, got {}", json::short_dump(arg)));
      d.kind_ = Kind::kIntegers;
    }
  } else if (key == "choice") {
    if (!arg.is_array() || arg.empty()) fail(sub, "expected a non-empty list of values");
    d.kind_ = Kind::kChoice;
    d.values_.assign(arg.begin(), arg.end());
  } else {
    fail(path + "." + key, "unknown distribution (known: uniform, log_uniform, integers, choice)");
  }
  return d;
}

nlohmann::json Distribution::draw(SampleRng& rng) const {
  switch (kind_) {
    case Kind::kFixed:
      return values_[0];
    case Kind::kUniform:
      return rng.uniform(lo_, hi_);
    case Kind::kLogUniform:
      return std::exp(rng.uniform(std::log(lo_), std::log(hi_)));
    case Kind::kIntegers:
      return rng.integer(static_cast<int64_t>(lo_), static_cast<int64_t>(hi_));
    case Kind::kChoice:
      return values_[static_cast<size_t>(rng.integer(0, static_cast<int64_t>(values_.size()) - 1))];
  }
  return nullptr;
}

double Distribution::draw_number(SampleRng& rng) const {
  return draw(rng).get<double>();
}

std::vector<nlohmann::json> Distribution::extremes() const {
  switch (kind_) {
    case Kind::kFixed:
    case Kind::kChoice:
      return values_;
    case Kind::kIntegers:
      return {static_cast<int64_t>(lo_), static_cast<int64_t>(hi_)};
    default:
      return {lo_, hi_};
  }
}

bool Distribution::numeric() const {
  for (const auto& v : extremes())
    if (!v.is_number()) return false;
  return true;
}

nlohmann::json Distribution::to_json() const {
  switch (kind_) {
    case Kind::kFixed:
      return values_[0];
    case Kind::kUniform:
      return {{"uniform", {lo_, hi_}}};
    case Kind::kLogUniform:
      return {{"log_uniform", {lo_, hi_}}};
    case Kind::kIntegers:
      return {{"integers", {static_cast<int64_t>(lo_), static_cast<int64_t>(hi_)}}};
    case Kind::kChoice:
      return {{"choice", values_}};
  }
  return nullptr;
}

}  // namespace pcisim::dataset
