#pragma once
// Helpers for the pcisim-remote tests: a gateway on in-process LCM (memq) listening on a free
// loopback port, a real WebSocket client on its own thread, and a recorder of what the gateway
// publishes on the bus.
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
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

namespace net = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
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

// a real WebSocket client: reads on its own thread into an inbox (unless told not to read)
class WsClient {
 public:
  WsClient() : ws_(io_) {}
  ~WsClient() { close_hard(); }

  // the HTTP status of the upgrade's answer: 101 when connected
  int connect(uint16_t port, const std::string& target, bool read = true, int receive_buffer = 0,
              const std::string& authorization = "") {
    auto& sock = beast::get_lowest_layer(ws_).socket();
    beast::error_code ec;
    sock.open(net::ip::tcp::v4());
    if (receive_buffer > 0) sock.set_option(net::socket_base::receive_buffer_size(receive_buffer));
    sock.connect({net::ip::address_v4::loopback(), port}, ec);
    if (ec) return -1;  // nothing listens
    if (!authorization.empty())
      ws_.set_option(websocket::stream_base::decorator([authorization](websocket::request_type& req) {
        req.set(beast::http::field::authorization, authorization);
      }));
    ws_.handshake("127.0.0.1", target, ec);
    if (ec) return upgrade_status(port, target, authorization);
    connected_ = true;
    if (read) start_reading();
    return 101;
  }

  // the status a refused upgrade got, asked again over plain HTTP (beast keeps no refused answer)
  static int upgrade_status(uint16_t port, const std::string& target, const std::string& authorization) {
    namespace http = beast::http;
    net::io_context io;
    beast::tcp_stream stream(io);
    beast::error_code ec;
    stream.connect({net::ip::address_v4::loopback(), port}, ec);
    if (ec) return -1;
    http::request<http::empty_body> req{http::verb::get, target, 11};
    req.set(http::field::host, "127.0.0.1");
    req.set(http::field::upgrade, "websocket");
    req.set(http::field::connection, "upgrade");
    req.set(http::field::sec_websocket_key, "dGhlIHNhbXBsZSBub25jZQ==");
    req.set(http::field::sec_websocket_version, "13");
    if (!authorization.empty()) req.set(http::field::authorization, authorization);
    http::write(stream, req, ec);
    beast::flat_buffer buf;
    http::response<http::string_body> res;
    http::read(stream, buf, res, ec);
    return ec ? -1 : res.result_int();
  }

  void start_reading() {
    read();
    thread_ = std::thread([this] { io_.run(); });
  }

  void send(const nlohmann::json& j) {
    auto text = std::make_shared<std::string>(j.dump());
    net::post(io_, [this, text] {
      outbox_.push_back(*text);
      if (!writing_) write_next();
    });
  }

  // the next message within timeout
  std::optional<WsMessage> next(std::chrono::milliseconds timeout = 3000ms) {
    std::unique_lock lock(mutex_);
    if (!cv_.wait_for(lock, timeout, [&] { return !inbox_.empty() || closed_; })) return std::nullopt;
    if (inbox_.empty()) return std::nullopt;
    WsMessage m = std::move(inbox_.front());
    inbox_.pop_front();
    return m;
  }

  // the next JSON message of this type (others are skipped; frames are counted)
  std::optional<nlohmann::json> next_of(const std::string& type, std::chrono::milliseconds timeout = 3000ms) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      auto m = next(std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now()));
      if (!m) return std::nullopt;
      if (m->binary) continue;
      auto j = m->json();
      if (j["type"] == type) return j;
    }
    return std::nullopt;
  }

  std::optional<WsMessage> next_frame(std::chrono::milliseconds timeout = 3000ms) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      auto m = next(std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now()));
      if (!m) return std::nullopt;
      if (m->binary) return m;
    }
    return std::nullopt;
  }

  bool closed() {
    std::lock_guard lock(mutex_);
    return closed_;
  }

  // drops the connection without a close frame, as a crashed page or a cut cable would
  void close_hard() {
    if (thread_.joinable()) {
      net::post(io_, [this] {
        beast::error_code ec;
        beast::get_lowest_layer(ws_).socket().shutdown(net::ip::tcp::socket::shutdown_both, ec);
        beast::get_lowest_layer(ws_).socket().close(ec);
      });
      thread_.join();
    } else if (connected_) {
      beast::error_code ec;
      beast::get_lowest_layer(ws_).socket().close(ec);
    }
    connected_ = false;
  }

 private:
  void read() {
    ws_.async_read(buf_, [this](beast::error_code ec, size_t) {
      std::lock_guard lock(mutex_);
      if (ec) {
        closed_ = true;
        cv_.notify_all();
        return;
      }
      inbox_.push_back({ws_.got_binary(), beast::buffers_to_string(buf_.data())});
      buf_.consume(buf_.size());
      cv_.notify_all();
      read();
    });
  }
  void write_next() {
    if (outbox_.empty()) return;
    writing_ = true;
    current_ = std::move(outbox_.front());
    outbox_.pop_front();
    ws_.text(true);
    ws_.async_write(net::buffer(current_), [this](beast::error_code ec, size_t) {
      writing_ = false;
      if (!ec) write_next();
    });
  }

  net::io_context io_;
  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buf_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<WsMessage> inbox_;
  bool closed_ = false, connected_ = false, writing_ = false;
  std::deque<std::string> outbox_;
  std::string current_;
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
