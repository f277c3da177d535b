#pragma once
// pcisim-remote's whole machine: LCM in (control bus and image bus, one thread each), an encoder
// thread (newest frame only), and one web thread serving the page and the WebSocket connections.
// The server never waits on a browser: nothing here publishes on the server's hot channels but
// session commands and, while enabled, the keyboard instrument.
#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "clients/remote/access_tokens.h"
#include "clients/remote/frame_encoder.h"
#include "clients/remote/hub.h"
#include "clients/remote/keyboard_instrument.h"
#include "clients/remote/latest_frame_slot.h"
#include "clients/remote/session_command_parser.h"
#include "clients/remote/session_tracker.h"

namespace pcisim::remote {

struct GatewayOptions {
  std::string bind = "127.0.0.1";
  uint16_t port = 8088;  // 0: any free port (port() says which)
  EncoderOptions encoder;
  HubLimits hub;
  CommandLimits commands;
  TrackerOptions tracker;
  KeyboardOptions keyboard;
  bool keyboard_instrument = true;
  double state_hz = 10;      // state messages per second
  std::string debrief_html;  // the server's debrief page on this host, served at /debrief.html ("": none)
};

struct GatewayCounters {
  // frames_received and frames_bad count X-ray frames; encoded, skipped and errors both kinds
  int64_t frames_received = 0, frames_bad = 0, frames_encoded = 0, frames_skipped = 0, encode_errors = 0;
  int64_t ultrasound_received = 0, ultrasound_bad = 0;
  int64_t control_bad = 0;
  double encode_ms_last = 0;
};

class Gateway {
 public:
  // the LCM instances must outlive the gateway; control and images may be the same URL but must be
  // different instances (each gets its own receive thread)
  Gateway(const GatewayOptions& options, lcm::LCM& control, lcm::LCM& images, AccessTokens tokens);
  ~Gateway();

  void start();  // binds (throws std::runtime_error naming the address) and starts the threads
  void stop();   // closes every connection, then the threads; idempotent
  uint16_t port() const { return port_; }
  const AccessTokens& tokens() const { return tokens_; }
  HubStats hub_stats() const { return hub_->stats(); }
  GatewayCounters counters() const;
  SessionTracker& tracker() { return tracker_; }
  KeyboardInstrument* keyboard() { return keyboard_.get(); }

 private:
  void accept();
  void tick();
  void encode_loop();
  void on_xray(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_ultrasound(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_wire(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_status(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_metrics(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_session(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_instrument(const lcm::ReceiveBuffer* rbuf, const std::string& channel);

  GatewayOptions options_;
  lcm::LCM& control_;
  lcm::LCM& images_;
  AccessTokens tokens_;
  SessionTracker tracker_;
  std::unique_ptr<KeyboardInstrument> keyboard_;
  std::unique_ptr<Hub> hub_;  // before io_: connections still in io_'s handlers outlive io_ only
  boost::asio::io_context io_;
  boost::asio::ip::tcp::acceptor acceptor_;
  boost::asio::steady_timer tick_timer_;
  uint16_t port_ = 0;
  std::atomic<bool> running_{false}, stopped_{false};
  std::thread io_thread_, control_thread_, image_thread_, encoder_thread_;
  LatestFrameSlot slot_;
  std::vector<lcm::Subscription*> control_subs_;
  std::vector<lcm::Subscription*> image_subs_;
  int64_t last_status_seq_ = -2, ticks_ = 0;
  // lcm receive buffers, one per thread's messages
  pcisim_lcm::xray_frame_t frame_in_;
  pcisim_lcm::us_frame_t us_frame_in_;
  pcisim_lcm::wire_state_t wire_in_;
  pcisim_lcm::sim_status_t status_in_;
  pcisim_lcm::session_metrics_t metrics_in_;
  pcisim_lcm::session_command_t session_in_;
  pcisim_lcm::instrument_state_t instrument_in_;
  std::atomic<int64_t> frames_received_{0}, frames_bad_{0}, frames_encoded_{0}, encode_errors_{0}, control_bad_{0};
  std::atomic<int64_t> ultrasound_received_{0}, ultrasound_bad_{0};
  std::atomic<double> encode_ms_last_{0};
};

}  // namespace pcisim::remote
