// The test WebSocket client's Beast code (remote_test_support.h): one translation unit, so the
// tests that use the client do not each compile Beast's websocket stream.
#include "remote_test_support.h"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

namespace pcisim::remote::test {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;

struct WsClient::Impl {
  Impl() : ws(io) {}

  // reads into the inbox until the connection ends
  void read() {
    ws.async_read(buf, [this](beast::error_code ec, size_t) {
      std::lock_guard lock(mutex);
      if (ec) {
        closed = true;
        cv.notify_all();
        return;
      }
      inbox.push_back({ws.got_binary(), beast::buffers_to_string(buf.data())});
      buf.consume(buf.size());
      cv.notify_all();
      read();
    });
  }
  void write_next() {
    if (outbox.empty()) return;
    writing = true;
    current = std::move(outbox.front());
    outbox.pop_front();
    ws.text(true);
    ws.async_write(net::buffer(current), [this](beast::error_code ec, size_t) {
      writing = false;
      if (!ec) write_next();
    });
  }

  net::io_context io;
  websocket::stream<beast::tcp_stream> ws;
  beast::flat_buffer buf;
  std::thread thread;
  std::mutex mutex;
  std::condition_variable cv;
  std::deque<WsMessage> inbox;
  bool closed = false, connected = false, writing = false;
  std::deque<std::string> outbox;
  std::string current;
};

WsClient::WsClient() : impl_(std::make_unique<Impl>()) {}

WsClient::~WsClient() {
  close_hard();
}

int WsClient::connect(uint16_t port, const std::string& target, bool read, int receive_buffer,
                      const std::string& authorization) {
  auto& sock = beast::get_lowest_layer(impl_->ws).socket();
  beast::error_code ec;
  sock.open(net::ip::tcp::v4());
  if (receive_buffer > 0) sock.set_option(net::socket_base::receive_buffer_size(receive_buffer));
  sock.connect({net::ip::address_v4::loopback(), port}, ec);
  if (ec) return -1;  // nothing listens
  if (!authorization.empty())
    impl_->ws.set_option(websocket::stream_base::decorator(
        [authorization](websocket::request_type& req) { req.set(beast::http::field::authorization, authorization); }));
  impl_->ws.handshake("127.0.0.1", target, ec);
  if (ec) return upgrade_status(port, target, authorization);
  impl_->connected = true;
  if (read) start_reading();
  return 101;
}

int WsClient::upgrade_status(uint16_t port, const std::string& target, const std::string& authorization) {
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

void WsClient::start_reading() {
  impl_->read();
  impl_->thread = std::thread([this] { impl_->io.run(); });
}

void WsClient::send(const nlohmann::json& j) {
  auto text = std::make_shared<std::string>(j.dump());
  net::post(impl_->io, [this, text] {
    impl_->outbox.push_back(*text);
    if (!impl_->writing) impl_->write_next();
  });
}

std::optional<WsMessage> WsClient::next(std::chrono::milliseconds timeout) {
  std::unique_lock lock(impl_->mutex);
  if (!impl_->cv.wait_for(lock, timeout, [&] { return !impl_->inbox.empty() || impl_->closed; })) return std::nullopt;
  if (impl_->inbox.empty()) return std::nullopt;
  WsMessage m = std::move(impl_->inbox.front());
  impl_->inbox.pop_front();
  return m;
}

std::optional<nlohmann::json> WsClient::next_of(const std::string& type, std::chrono::milliseconds timeout) {
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

std::optional<WsMessage> WsClient::next_frame(std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    auto m = next(std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now()));
    if (!m) return std::nullopt;
    if (m->binary) return m;
  }
  return std::nullopt;
}

bool WsClient::closed() {
  std::lock_guard lock(impl_->mutex);
  return impl_->closed;
}

void WsClient::close_hard() {
  if (impl_->thread.joinable()) {
    net::post(impl_->io, [this] {
      beast::error_code ec;
      beast::get_lowest_layer(impl_->ws).socket().shutdown(net::ip::tcp::socket::shutdown_both, ec);
      beast::get_lowest_layer(impl_->ws).socket().close(ec);
    });
    impl_->thread.join();
  } else if (impl_->connected) {
    beast::error_code ec;
    beast::get_lowest_layer(impl_->ws).socket().close(ec);
  }
  impl_->connected = false;
}

}  // namespace pcisim::remote::test
