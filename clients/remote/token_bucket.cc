#include "clients/remote/token_bucket.h"

#include <algorithm>

namespace pcisim::remote {

bool TokenBucket::try_take(int64_t now_ns) {
  if (last_ns_ >= 0 && now_ns > last_ns_) tokens_ = std::min(burst_, tokens_ + (now_ns - last_ns_) * 1e-9 * rate_);
  if (last_ns_ < 0 || now_ns > last_ns_) last_ns_ = now_ns;
  if (tokens_ < 1.0) return false;
  tokens_ -= 1.0;
  return true;
}

}  // namespace pcisim::remote
