#pragma once
// The dataset's random numbers: SplitMix64 (Steele, Lea & Flood, OOPSLA 2014), written out here so
// a sample's draws are the same on every machine and standard library (std::uniform_*_distribution
// is not specified bit for bit). Each sample gets its own stream from (spec seed, sample index):
// a shard draws sample 417 exactly as a single run does.
#include <cmath>
#include <cstdint>

namespace pcisim::dataset {

class SampleRng {
 public:
  explicit SampleRng(uint64_t seed) : state_(seed) {}
  // the stream of sample `index` of a spec seeded `spec_seed`; `stream` separates independent
  // uses within a sample (parameters, instrument driver, noise) so adding a draw to one does not
  // move the others
  static SampleRng for_sample(uint64_t spec_seed, uint64_t index, uint64_t stream) {
    SampleRng r(spec_seed * 0x9E3779B97F4A7C15ull ^ (index + 1) * 0xBF58476D1CE4E5B9ull ^
                (stream + 1) * 0x94D049BB133111EBull);
    r.next();
    return r;
  }

  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // [0, 1) with 53 random bits
  double uniform01() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform01(); }
  // an integer in [lo, hi], both included
  int64_t integer(int64_t lo, int64_t hi) {
    const uint64_t span = static_cast<uint64_t>(hi - lo) + 1;
    return lo + static_cast<int64_t>(span == 0 ? next() : next() % span);
  }

 private:
  uint64_t state_;
};

}  // namespace pcisim::dataset
