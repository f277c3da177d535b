#pragma once
// Helpers for the pcisim-remote tests: a gateway on in-process LCM (memq) listening on a free
// loopback port, a real WebSocket client on its own thread, and a recorder of what the gateway
// publishes on the bus.
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <thread>
#include <vector>

#include "clients/remote/gateway.h"
#include "protocol/channels.h"
#include "protocol/message_checks.h"

namespace pcisim::remote::test {

using namespace std::chrono_literals;

inline const char* kObserverToken = "observer-token-0123456789abcdef";
inline const char* kControllerToken = "controller-token-0123456789abcdef";

// every session command the gateway publishes
struct CommandRecorder {
  std::mutex mutex;
  std::vector<pcisim_lcm::session_command_t> commands;
  void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    pcisim_lcm::session_command_t c;
    if (!protocol::decode_checked(*rbuf, c)) return;
    std::lock_guard lock(mutex);
    commands.push_back(c);
  }
  std::vector<pcisim_lcm::session_command_t> all() {
    std::lock_guard lock(mutex);
    return commands;
  }
};

struct TestGateway {
  explicit TestGateway(GatewayOptions options = {}, bool start_now = true) : options_(fix(options)) {
    control.subscribe(protocol::kSessionChannel, &CommandRecorder::on, &recorder);
    gateway = std::make_unique<Gateway>(options_, control, images, AccessTokens(kObserverToken, kControllerToken));
    if (start_now) gateway->start();
  }
  static GatewayOptions fix(GatewayOptions o) {
    o.port = 0;
    o.bind = "127.0.0.1";
    return o;
  }
  uint16_t port() const { return gateway->port(); }
  GatewayOptions options_;
  lcm::LCM control{"memq://"};
  lcm::LCM images{"memq://"};
  CommandRecorder recorder;
  std::unique_ptr<Gateway> gateway;
};

struct WsMessage {
  bool binary = false;
  std::string data;
  nlohmann::json json() const { return nlohmann::json::parse(data); }
  uint32_t header_bytes() const {
    uint32_t n = 0;
    for (int k = 3; k >= 0; --k) n = n << 8 | static_cast<uint8_t>(data[k]);
    return n;
  }
  // a frame's JSON header and image file
  nlohmann::json frame_header() const { return nlohmann::json::parse(data.substr(4, header_bytes())); }
  std::string image() const { return data.substr(4 + header_bytes()); }
};

// a real WebSocket client: reads on its own thread into an inbox (unless told not to read). Its
// Beast code lives in remote_test_support.cc, compiled once for every test file that uses it.
class WsClient {
 public:
  WsClient();
  ~WsClient();
  WsClient(const WsClient&) = delete;
  WsClient& operator=(const WsClient&) = delete;

  // the HTTP status of the upgrade's answer: 101 when connected
  int connect(uint16_t port, const std::string& target, bool read = true, int receive_buffer = 0,
              const std::string& authorization = "");
  // the status a refused upgrade got, asked again over plain HTTP (beast keeps no refused answer)
  static int upgrade_status(uint16_t port, const std::string& target, const std::string& authorization);
  void start_reading();
  void send(const nlohmann::json& j);
  // the next message within timeout
  std::optional<WsMessage> next(std::chrono::milliseconds timeout = 3000ms);
  // the next JSON message of this type (others are skipped; frames are counted)
  std::optional<nlohmann::json> next_of(const std::string& type, std::chrono::milliseconds timeout = 3000ms);
  std::optional<WsMessage> next_frame(std::chrono::milliseconds timeout = 3000ms);
  bool closed();
  // drops the connection without a close frame, as a crashed page or a cut cable would
  void close_hard();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

inline std::string ws_target(const char* token) {
  return std::string("/ws?token=") + token;
}

// a 16-bit frame: a gradient plus noise (noise makes it as costly to encode as a real one)
inline pcisim_lcm::xray_frame_t make_frame(int64_t seq, int size = 256, uint16_t base = 0, unsigned noise_seed = 1) {
  pcisim_lcm::xray_frame_t f{};
  f.seq = seq;
  f.width = f.height = size;
  f.pixel_format = pcisim_lcm::xray_frame_t::FORMAT_GRAY16;
  f.primary_angle_deg = -30;
  f.secondary_angle_deg = 30;
  f.cine_run = -1;
  f.num_bytes = size * size * 2;
  f.data.resize(static_cast<size_t>(f.num_bytes));
  std::mt19937 rng(noise_seed + static_cast<unsigned>(seq));
  for (int i = 0; i < size * size; ++i) {
    const int v = std::clamp(base + (i % size) * 200 + static_cast<int>(rng() % 4096), 0, 65535);
    f.data[2 * i] = static_cast<uint8_t>(v & 0xff);
    f.data[2 * i + 1] = static_cast<uint8_t>(v >> 8);
  }
  return f;
}

// waits until pred() holds or timeout passes
inline bool eventually(const std::function<bool()>& pred, std::chrono::milliseconds timeout = 3000ms) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (pred()) return true;
    std::this_thread::sleep_for(5ms);
  }
  return pred();
}

}  // namespace pcisim::remote::test
