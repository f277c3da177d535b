#include "clients/remote/ws_session.h"

#include "clients/remote/hub.h"

namespace pcisim::remote {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
using Clock = std::chrono::steady_clock;

WsSession::WsSession(boost::asio::ip::tcp::socket&& socket, Hub& hub, Role role, double max_fps)
    : ws_(std::move(socket)),
      frame_timer_(ws_.get_executor()),
      hub_(hub),
      role_(role),
      max_fps_(max_fps),
      commands_(hub.limits().command_rate, hub.limits().command_burst),
      keys_(hub.limits().keys_rate, hub.limits().keys_burst) {}

WsSession::~WsSession() {
  // what was held for this connection is no longer pending
  if (pending_frame_) hub_.count_frame_pending(-static_cast<int64_t>(pending_frame_->message.size()));
  if (writing_frame_) hub_.count_frame_pending(-static_cast<int64_t>(writing_frame_->message.size()));
}

void WsSession::start(beast::http::request<beast::http::string_body> request) {
  auto timeouts = websocket::stream_base::timeout::suggested(beast::role_type::server);
  timeouts.idle_timeout = std::chrono::seconds(20);  // pings keep a live page; a dead one is dropped
  timeouts.keep_alive_pings = true;
  ws_.set_option(timeouts);
  ws_.read_message_max(hub_.limits().max_message_bytes);
  ws_.set_option(websocket::stream_base::decorator(
      [](websocket::response_type& res) { res.set(beast::http::field::server, "pcisim-remote"); }));
  ws_.async_accept(request, beast::bind_front_handler(&WsSession::on_accept, shared_from_this()));
}

void WsSession::on_accept(beast::error_code ec) {
  if (ec) return;
  open_ = true;
  id_ = hub_.join(shared_from_this());
  read();
}

void WsSession::read() {
  ws_.async_read(in_, beast::bind_front_handler(&WsSession::on_read, shared_from_this()));
}

void WsSession::on_read(beast::error_code ec, size_t) {
  if (ec) return fail();
  if (ws_.got_text()) hub_.on_text(*this, beast::buffers_to_string(in_.data()));
  in_.consume(in_.size());
  read();
}

void WsSession::fail() {
  if (gone_) return;
  gone_ = true;
  open_ = false;
  frame_timer_.cancel();
  hub_.leave(*this);
}

void WsSession::set_max_fps(double fps) {
  max_fps_ = fps;
}

void WsSession::offer_frame(std::shared_ptr<const EncodedFrame> frame) {
  if (!open_) return;
  if (pending_frame_) {
    // latest wins: the unsent frame is stale
    ++frames_dropped_;
    hub_.count_frame_dropped(pending_frame_->message.size());
    hub_.count_frame_pending(-static_cast<int64_t>(pending_frame_->message.size()));
  }
  pending_frame_ = std::move(frame);
  hub_.count_frame_pending(static_cast<int64_t>(pending_frame_->message.size()));
  pump();
}

void WsSession::offer_state(std::shared_ptr<const std::string> state) {
  if (!open_) return;
  pending_state_ = std::move(state);
  pump();
}

void WsSession::offer_status(std::shared_ptr<const std::string> status) {
  if (!open_) return;
  pending_status_ = std::move(status);
  pump();
}

void WsSession::reply(std::string text) {
  if (!open_) return;
  if (replies_.size() >= hub_.limits().max_replies) replies_.pop_front();
  replies_.push_back(std::move(text));
  pump();
}

void WsSession::close() {
  if (!open_ || closing_) return;
  closing_ = true;
  frame_timer_.cancel();
  if (writing_) return;  // on_write closes once the write in flight is done
  ws_.async_close(websocket::close_code::going_away, [self = shared_from_this()](beast::error_code) { self->fail(); });
}

void WsSession::pump() {
  if (!open_ || writing_ || closing_) return;
  auto self = shared_from_this();
  auto write_text = [&](const std::string& text) {
    writing_ = true;
    ws_.text(true);
    ws_.async_write(boost::asio::buffer(text), beast::bind_front_handler(&WsSession::on_write, self));
  };
  if (!replies_.empty()) {
    writing_reply_ = std::move(replies_.front());
    replies_.pop_front();
    return write_text(writing_reply_);
  }
  if (pending_status_) {
    writing_text_ = std::move(pending_status_);
    return write_text(*writing_text_);
  }
  if (pending_state_) {
    writing_text_ = std::move(pending_state_);
    return write_text(*writing_text_);
  }
  if (!pending_frame_) return;
  // this page's frame rate: hold the newest frame until its turn (a newer one may replace it)
  const auto min_gap = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / max_fps_));
  const auto now = Clock::now();
  if (now - last_frame_sent_ < min_gap) {
    if (!timer_armed_) {
      timer_armed_ = true;
      frame_timer_.expires_at(last_frame_sent_ + min_gap);
      frame_timer_.async_wait([self](beast::error_code ec) {
        self->timer_armed_ = false;
        if (!ec) self->pump();
      });
    }
    return;
  }
  last_frame_sent_ = now;
  writing_frame_ = std::move(pending_frame_);
  writing_ = true;
  ws_.binary(true);
  ws_.async_write(boost::asio::buffer(writing_frame_->message), beast::bind_front_handler(&WsSession::on_write, self));
}

void WsSession::on_write(beast::error_code ec, size_t) {
  writing_ = false;
  writing_text_.reset();
  if (writing_frame_) {
    hub_.count_frame_pending(-static_cast<int64_t>(writing_frame_->message.size()));
    if (!ec) {
      ++frames_sent_;
      hub_.count_frame_sent(writing_frame_->message.size());
    }
    writing_frame_.reset();
  }
  if (ec) return fail();
  if (closing_) {
    closing_ = false;  // let close() run now that nothing is in flight
    return close();
  }
  pump();
}

}  // namespace pcisim::remote
