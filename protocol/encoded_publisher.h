#pragma once
// Publishes LCM messages through one encode buffer, kept between calls: lcm-cpp's templated
// publish allocates a buffer of the message's size on every call (new[] in lcm-cpp.hpp), which on
// the server's output path meant one allocation per force command at 1 kHz and half a megabyte
// per X-ray frame. The buffer grows to the largest message published through it and stays; after
// the first message of each size nothing is allocated here (liblcm's own transport may still
// malloc: memq copies each message). One publisher per sending thread.
#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace pcisim::protocol {

class EncodedPublisher {
 public:
  explicit EncodedPublisher(size_t reserve_bytes = 0) { buffer_.reserve(reserve_bytes); }

  // encodes m and publishes it on channel; returns lcm's status (0 on success), -1 when the
  // message would not encode
  template <class Message>
  int publish(lcm::LCM& lcm, const std::string& channel, const Message& m) {
    const int size = m.getEncodedSize();
    if (size < 0) return -1;
    if (buffer_.size() < static_cast<size_t>(size)) {
      buffer_.resize(static_cast<size_t>(size));
      ++grown_;
    }
    if (m.encode(buffer_.data(), 0, size) != size) return -1;
    return lcm.publish(channel, buffer_.data(), static_cast<unsigned>(size));
  }

  // room for a message of this size up front (a loop whose first message must not allocate)
  void reserve(size_t bytes) { buffer_.reserve(bytes); }

  // how often the buffer had to grow (a steady stream of one size: once)
  int64_t grown() const { return grown_; }

 private:
  std::vector<uint8_t> buffer_;
  int64_t grown_ = 0;
};

}  // namespace pcisim::protocol
