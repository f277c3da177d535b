#pragma once
// The connections and what they may do. Lives on the web thread: every method but stats() runs
// there. Frames, state and status go out latest-wins; commands come in, are checked for role,
// rate and range, and go to the server's session channel.
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "clients/remote/access_tokens.h"
#include "clients/remote/frame_encoder.h"
#include "clients/remote/session_command_parser.h"
#include "pcisim_lcm/session_command_t.hpp"

namespace pcisim::remote {

class WsSession;
class KeyboardInstrument;
class SessionTracker;

struct HubLimits {
  double max_fps = 30;                          // per connection; a page may ask for less
  double command_rate = 5, command_burst = 10;  // session commands per second, per connection
  double keys_rate = 40, keys_burst = 80;       // keyboard-instrument updates
  size_t max_clients = 64;
  size_t max_replies = 16;              // queued answers per connection, oldest dropped
  size_t max_message_bytes = 4096;      // a page's message; bigger closes the connection
  int socket_send_buffer = 256 * 1024;  // kernel send buffer per connection (0: the OS's):
                                        // frames queued there are stale frames too
};

struct HubStats {
  int64_t clients = 0, connections_total = 0;
  int64_t frames_offered = 0, frames_sent = 0, frames_dropped = 0;
  int64_t bytes_pending = 0;  // frame bytes held for connections that have not taken them
  int64_t commands_forwarded = 0, commands_refused = 0, rate_limited = 0;
};

class Hub {
 public:
  using CommandSink = std::function<void(const pcisim_lcm::session_command_t&)>;
  Hub(const HubLimits& limits, const CommandLimits& command_limits, CommandSink sink, SessionTracker& tracker,
      KeyboardInstrument* keyboard);

  // no room for one more connection of this role: observers leave one slot free, so a crowd of
  // observers never locks the controller out (64 observers once did)
  bool full(Role role) const;
  uint64_t join(const std::shared_ptr<WsSession>& session);  // sends hello and the latest of everything
  void leave(WsSession& session);                            // releases what the connection held
  void on_text(WsSession& session, const std::string& text);

  void broadcast_frame(std::shared_ptr<const EncodedFrame> frame);
  void broadcast_state(std::shared_ptr<const std::string> state);
  void broadcast_status(std::shared_ptr<const std::string> status);
  void close_all();  // shutdown: every connection gets a close frame

  const HubLimits& limits() const { return limits_; }
  HubStats stats() const;  // any thread
  // called by sessions to keep the counters
  void count_frame_sent(size_t bytes);
  void count_frame_dropped(size_t bytes);
  void count_frame_pending(int64_t delta_bytes);

 private:
  void handle(WsSession& s, const nlohmann::json& msg);
  void send_pedal(bool cine, bool down);

  HubLimits limits_;
  CommandLimits command_limits_;
  CommandSink sink_;
  SessionTracker& tracker_;
  KeyboardInstrument* keyboard_;
  std::map<uint64_t, std::weak_ptr<WsSession>> sessions_;
  uint64_t next_id_ = 1;
  std::shared_ptr<const EncodedFrame> last_frame_;
  std::shared_ptr<const std::string> last_state_, last_status_;
  std::atomic<int64_t> clients_{0}, connections_total_{0}, frames_offered_{0}, frames_sent_{0}, frames_dropped_{0},
      bytes_pending_{0}, commands_forwarded_{0}, commands_refused_{0}, rate_limited_{0};
};

}  // namespace pcisim::remote
