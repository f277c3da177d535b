#pragma once
// One WebSocket connection. Its outbox never grows: one slot each for the newest frame, state and
// status (a newer one replaces an unsent one: stale frames are dropped, counted) plus a short
// queue of answers. Only one write is in flight; a slow page simply gets fewer frames.
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <deque>
#include <memory>
#include <string>

#include "clients/remote/access_tokens.h"
#include "clients/remote/frame_encoder.h"
#include "clients/remote/token_bucket.h"

namespace pcisim::remote {

class Hub;

class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(boost::asio::ip::tcp::socket&& socket, Hub& hub, Role role, double max_fps);
  ~WsSession();
  // completes the upgrade the HTTP session read
  void start(boost::beast::http::request<boost::beast::http::string_body> request);

  void offer_frame(std::shared_ptr<const EncodedFrame> frame);
  void offer_state(std::shared_ptr<const std::string> state);
  void offer_status(std::shared_ptr<const std::string> status);
  void reply(std::string text);
  void close();  // going away

  uint64_t id() const { return id_; }
  Role role() const { return role_; }
  void set_max_fps(double fps);
  double max_fps() const { return max_fps_; }
  TokenBucket& command_bucket() { return commands_; }
  TokenBucket& keys_bucket() { return keys_; }
  // pedals this connection holds down: released if it goes away
  bool holds_fluoro = false, holds_cine = false;
  int64_t frames_sent() const { return frames_sent_; }
  int64_t frames_dropped() const { return frames_dropped_; }

 private:
  void on_accept(boost::beast::error_code ec);
  void read();
  void on_read(boost::beast::error_code ec, size_t bytes);
  void pump();
  void on_write(boost::beast::error_code ec, size_t bytes);
  void fail();

  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
  boost::beast::flat_buffer in_;
  boost::asio::steady_timer frame_timer_;
  Hub& hub_;
  Role role_;
  uint64_t id_ = 0;
  double max_fps_;
  TokenBucket commands_, keys_;
  bool open_ = false, writing_ = false, closing_ = false, timer_armed_ = false, gone_ = false;
  std::shared_ptr<const EncodedFrame> pending_frame_, writing_frame_;
  std::shared_ptr<const std::string> pending_state_, pending_status_, writing_text_;
  std::deque<std::string> replies_;
  std::string writing_reply_;
  std::chrono::steady_clock::time_point last_frame_sent_{};
  int64_t frames_sent_ = 0, frames_dropped_ = 0;
};

}  // namespace pcisim::remote
