#pragma once
// A token bucket: bursts up to `burst` messages, then `rate_per_s` on average. Each connection
// has its own, so one noisy page cannot flood the server's session channel.
#include <cstdint>

namespace pcisim::remote {

class TokenBucket {
 public:
  TokenBucket(double rate_per_s, double burst) : rate_(rate_per_s), burst_(burst), tokens_(burst) {}
  // takes one token if there is one at time now_ns (monotonic)
  bool try_take(int64_t now_ns);
  double tokens() const { return tokens_; }

 private:
  double rate_, burst_, tokens_;
  int64_t last_ns_ = -1;
};

}  // namespace pcisim::remote
