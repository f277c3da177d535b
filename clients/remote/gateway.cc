#include "clients/remote/gateway.h"

#include <boost/asio/post.hpp>
#include <boost/asio/strand.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "clients/remote/http_session.h"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/clock.h"

namespace pcisim::remote {

namespace net = boost::asio;
using net::ip::tcp;
using realtime::monotonic_ns;

Gateway::Gateway(const GatewayOptions& options, lcm::LCM& control, lcm::LCM& images, AccessTokens tokens)
    : options_(options),
      control_(control),
      images_(images),
      tokens_(std::move(tokens)),
      tracker_([&] {
        TrackerOptions t = options.tracker;
        t.own_device_id = options.keyboard.device_id;
        return t;
      }()),
      acceptor_(io_),
      tick_timer_(io_) {
  if (&control == &images) throw std::invalid_argument("the control and image buses need separate LCM instances");
  if (options_.keyboard_instrument)
    keyboard_ = std::make_unique<KeyboardInstrument>(
        control_, options_.keyboard, [this] { return tracker_.other_instrument_active(monotonic_ns()); });
  auto sink = [this](const pcisim_lcm::session_command_t& c) { control_.publish(protocol::kSessionChannel, &c); };
  hub_ = std::make_unique<Hub>(options_.hub, options_.commands, sink, tracker_, keyboard_.get());
  control_subs_ = {control_.subscribe(protocol::kWireChannel, &Gateway::on_wire, this),
                   control_.subscribe(protocol::kStatusChannel, &Gateway::on_status, this),
                   control_.subscribe(protocol::kMetricsChannel, &Gateway::on_metrics, this),
                   control_.subscribe(protocol::kSessionChannel, &Gateway::on_session, this),
                   control_.subscribe(protocol::kInstrumentChannel, &Gateway::on_instrument, this)};
  // the scene sends whichever modality it has; the page shows what comes
  image_subs_ = {images_.subscribe(protocol::kXrayChannel, &Gateway::on_xray, this),
                 images_.subscribe(protocol::kUltrasoundChannel, &Gateway::on_ultrasound, this)};
}

Gateway::~Gateway() {
  stop();
  // the LCM instances outlive us: no handler may point here afterwards
  for (auto* sub : control_subs_) control_.unsubscribe(sub);
  for (auto* sub : image_subs_) images_.unsubscribe(sub);
}

void Gateway::start() {
  boost::system::error_code ec;
  const auto address = net::ip::make_address(options_.bind, ec);
  if (ec) throw std::runtime_error(fmt::format("--bind {}: not an IP address", options_.bind));
  const tcp::endpoint endpoint(address, options_.port);
  acceptor_.open(endpoint.protocol(), ec);
  if (!ec) acceptor_.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) acceptor_.bind(endpoint, ec);
  if (!ec) acceptor_.listen(net::socket_base::max_listen_connections, ec);
  if (ec)
    throw std::runtime_error(fmt::format("cannot listen on {}:{}: {}", options_.bind, options_.port, ec.message()));
  port_ = acceptor_.local_endpoint().port();
  running_ = true;
  accept();
  tick();
  io_thread_ = std::thread([this] { io_.run(); });
  control_thread_ = std::thread([this] {
    while (running_) control_.handleTimeout(20);
  });
  image_thread_ = std::thread([this] {
    while (running_) images_.handleTimeout(20);
  });
  encoder_thread_ = std::thread([this] { encode_loop(); });
}

void Gateway::stop() {
  if (!running_ || stopped_.exchange(true)) return;
  // connections first (pedals they held are released while the bus still runs), then threads
  net::post(io_, [this] {
    boost::system::error_code ignored;
    acceptor_.close(ignored);
    tick_timer_.cancel();
    hub_->close_all();
  });
  // close frames get a moment to leave; a page that does not answer is cut off
  for (int i = 0; i < 50 && hub_->stats().clients > 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  io_.stop();
  io_thread_.join();
  running_ = false;
  slot_.wake();
  encoder_thread_.join();
  control_thread_.join();
  image_thread_.join();
  keyboard_.reset();
}

void Gateway::accept() {
  acceptor_.async_accept(net::make_strand(io_), [this](boost::system::error_code ec, tcp::socket socket) {
    if (ec == net::error::operation_aborted || !acceptor_.is_open()) return;
    if (!ec) {
      socket.set_option(tcp::no_delay(true), ec);
      if (options_.hub.socket_send_buffer > 0)
        socket.set_option(net::socket_base::send_buffer_size(options_.hub.socket_send_buffer), ec);
      std::make_shared<HttpSession>(std::move(socket), *hub_, tokens_, options_.debrief_html)->run();
    }
    accept();
  });
}

// the web thread's clock: state at state_hz, status whenever the server sent a new one
void Gateway::tick() {
  const int64_t now_ns = monotonic_ns();
  nlohmann::json state = tracker_.state_json(now_ns);
  if (keyboard_) {
    state["keyboard"] = {{"owner", keyboard_->owner()},
                         {"insertion_mm", keyboard_->insertion_mm()},
                         {"rotation_rad", keyboard_->rotation_rad()},
                         {"stopped_because", keyboard_->stop_reason()}};
  }
  const HubStats hs = hub_->stats();
  state["gateway"] = {{"clients", hs.clients},
                      {"frames_received", frames_received_.load()},
                      {"ultrasound_received", ultrasound_received_.load()},
                      {"frames_encoded", frames_encoded_.load()},
                      {"frames_dropped", hs.frames_dropped},
                      {"encode_ms", encode_ms_last_.load()}};
  hub_->broadcast_state(std::make_shared<const std::string>(state.dump()));
  if (const int64_t seq = tracker_.status_seq(); seq != last_status_seq_ && seq >= 0) {
    last_status_seq_ = seq;
    hub_->broadcast_status(std::make_shared<const std::string>(tracker_.status_json(now_ns).dump()));
  }
  ++ticks_;
  tick_timer_.expires_after(std::chrono::microseconds(static_cast<int64_t>(1e6 / options_.state_hz)));
  tick_timer_.async_wait([this](boost::system::error_code ec) {
    if (!ec) tick();
  });
}

void Gateway::encode_loop() {
  FrameEncoder encoder(options_.encoder);
  pcisim_lcm::xray_frame_t xray;
  pcisim_lcm::us_frame_t us;
  auto encode = [&](const auto& frame) {
    const int64_t t0 = monotonic_ns();
    try {
      auto encoded = encoder.encode(frame);
      encode_ms_last_ = (monotonic_ns() - t0) * 1e-6;
      ++frames_encoded_;
      net::post(io_, [this, encoded = std::move(encoded)]() mutable { hub_->broadcast_frame(std::move(encoded)); });
    } catch (const std::exception& e) {
      if (encode_errors_++ == 0) spdlog::warn("remote: cannot show a frame: {}", e.what());
    }
  };
  while (running_) {
    const int taken = slot_.take(xray, us, 100);
    if (taken & LatestFrameSlot::kXray) encode(xray);
    if (taken & LatestFrameSlot::kUltrasound) encode(us);
  }
}

void Gateway::on_xray(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  if (!protocol::decode_checked(*rbuf, frame_in_)) {
    ++frames_bad_;
    return;
  }
  ++frames_received_;
  tracker_.on_frame(frame_in_, monotonic_ns());
  slot_.put(frame_in_);
}

void Gateway::on_ultrasound(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  if (!protocol::decode_checked(*rbuf, us_frame_in_)) {
    ++ultrasound_bad_;
    return;
  }
  ++ultrasound_received_;
  slot_.put(us_frame_in_);
}

void Gateway::on_wire(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  if (protocol::decode_checked(*rbuf, wire_in_))
    tracker_.on_wire(wire_in_, monotonic_ns());
  else
    ++control_bad_;
}

void Gateway::on_status(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  if (protocol::decode_checked(*rbuf, status_in_))
    tracker_.on_status(status_in_, monotonic_ns());
  else
    ++control_bad_;
}

void Gateway::on_metrics(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  if (protocol::decode_checked(*rbuf, metrics_in_))
    tracker_.on_metrics(metrics_in_, monotonic_ns());
  else
    ++control_bad_;
}

void Gateway::on_session(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  if (protocol::decode_checked(*rbuf, session_in_))
    tracker_.on_session(session_in_, monotonic_ns());
  else
    ++control_bad_;
}

void Gateway::on_instrument(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  if (protocol::decode_checked(*rbuf, instrument_in_))
    tracker_.on_instrument(instrument_in_, monotonic_ns());
  else
    ++control_bad_;
}

GatewayCounters Gateway::counters() const {
  GatewayCounters c;
  c.frames_received = frames_received_;
  c.frames_bad = frames_bad_;
  c.frames_encoded = frames_encoded_;
  c.frames_skipped = slot_.replaced();
  c.encode_errors = encode_errors_;
  c.control_bad = control_bad_;
  c.ultrasound_received = ultrasound_received_;
  c.ultrasound_bad = ultrasound_bad_;
  c.encode_ms_last = encode_ms_last_;
  return c;
}

}  // namespace pcisim::remote
