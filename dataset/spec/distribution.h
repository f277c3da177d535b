#pragma once
// One value of a dataset spec that varies from sample to sample. In the spec it is written as a
// plain JSON value (always that value) or as one of
//   {"uniform": [a, b]}      a real number, evenly in [a, b]
//   {"log_uniform": [a, b]}  a real number whose logarithm is even in [ln a, ln b] (0 < a <= b)
//   {"integers": [a, b]}     a whole number, each of a..b equally likely
//   {"choice": [v1, v2, ...]} one of the values, each equally likely (any JSON values)
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "dataset/spec/sample_rng.h"

namespace pcisim::dataset {

class Distribution {
 public:
  enum class Kind { kFixed, kUniform, kLogUniform, kIntegers, kChoice };

  // throws json::JsonError naming `path` and what was expected
  static Distribution parse(const nlohmann::json& value, const std::string& path);
  static Distribution fixed(nlohmann::json value);

  nlohmann::json draw(SampleRng& rng) const;
  double draw_number(SampleRng& rng) const;  // the same for a numeric distribution
  // the values a check must try to cover every draw: the ends of a range, every choice
  std::vector<nlohmann::json> extremes() const;
  bool numeric() const;  // every draw is a number
  Kind kind() const { return kind_; }
  nlohmann::json to_json() const;  // as the spec writes it

 private:
  Kind kind_ = Kind::kFixed;
  double lo_ = 0, hi_ = 0;
  std::vector<nlohmann::json> values_;  // fixed: one; choice: all
};

}  // namespace pcisim::dataset
