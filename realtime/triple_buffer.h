#pragma once
// Single writer, single reader, latest wins. Neither side ever waits or allocates: the writer
// fills its private slot and swaps it into the middle; the reader swaps the middle out when it
// is newer than what it holds.
#include <array>
#include <atomic>
#include <cstdint>

namespace pcisim::realtime {

template <class T>
class TripleBuffer {
 public:
  TripleBuffer() = default;
  explicit TripleBuffer(const T& initial) : slots_{initial, initial, initial} {}

  // writer side: fill write_slot(), then publish()
  T& write_slot() { return slots_[write_]; }
  void publish() {
    write_ = middle_.exchange(static_cast<uint8_t>(write_ | kFresh), std::memory_order_acq_rel) & kIndex;
  }

  // reader side: take the newest published value; true when it changed since the last call
  bool refresh() {
    if (!(middle_.load(std::memory_order_acquire) & kFresh)) return false;
    read_ = middle_.exchange(read_, std::memory_order_acq_rel) & kIndex;
    return true;
  }
  const T& read_slot() const { return slots_[read_]; }

 private:
  static constexpr uint8_t kIndex = 0x3, kFresh = 0x4;
  std::array<T, 3> slots_{};
  std::atomic<uint8_t> middle_{1};
  uint8_t write_ = 0;  // touched by the writer only
  uint8_t read_ = 2;   // touched by the reader only
};

}  // namespace pcisim::realtime
