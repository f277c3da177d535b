#include "clients/remote/hub.h"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "clients/remote/keyboard_instrument.h"
#include "clients/remote/session_tracker.h"
#include "clients/remote/ws_session.h"
#include "realtime/clock.h"

namespace pcisim::remote {

using nlohmann::json;
using C = pcisim_lcm::session_command_t;

Hub::Hub(const HubLimits& limits, const CommandLimits& command_limits, CommandSink sink, SessionTracker& tracker,
         KeyboardInstrument* keyboard)
    : limits_(limits),
      command_limits_(command_limits),
      sink_(std::move(sink)),
      tracker_(tracker),
      keyboard_(keyboard) {}

bool Hub::full(Role role) const {
  if (sessions_.size() >= limits_.max_clients) return true;
  if (role == Role::kController) return false;
  size_t observers = 0;
  for (const auto& [id, weak] : sessions_)
    if (const auto s = weak.lock(); s && s->role() == Role::kObserver) ++observers;
  return observers + 1 >= limits_.max_clients;
}

uint64_t Hub::join(const std::shared_ptr<WsSession>& s) {
  const uint64_t id = next_id_++;
  sessions_[id] = s;
  ++clients_;
  ++connections_total_;
  spdlog::info("remote: connection {} joined as {} ({} open)", id, role_name(s->role()), sessions_.size());
  json hello = {{"type", "hello"},
                {"id", id},
                {"role", role_name(s->role())},
                {"limits",
                 {{"max_fps", limits_.max_fps},
                  {"command_rate", limits_.command_rate},
                  {"command_burst", limits_.command_burst},
                  {"primary_abs_deg", command_limits_.primary_abs_deg},
                  {"secondary_abs_deg", command_limits_.secondary_abs_deg},
                  {"contrast_ml", {command_limits_.contrast_ml_min, command_limits_.contrast_ml_max}}}},
                {"keyboard_instrument", keyboard_ != nullptr}};
  s->reply(hello.dump());
  // a late joiner sees the last image held, as a cath-lab monitor does
  if (last_status_) s->offer_status(last_status_);
  if (last_state_) s->offer_state(last_state_);
  if (last_frame_) s->offer_frame(last_frame_);
  return id;
}

void Hub::send_pedal(bool cine, bool down) {
  C c{};
  c.utime = realtime::monotonic_us();
  c.command = cine ? C::CMD_CINE : C::CMD_FLUORO_PEDAL;
  c.pedal_down = down ? 1 : 0;
  sink_(c);
}

void Hub::leave(WsSession& s) {
  if (sessions_.erase(s.id()) == 0) return;
  --clients_;
  // a page that goes away must not leave the wire moving or the beam on
  if (keyboard_) keyboard_->disable(s.id());
  if (s.holds_fluoro) send_pedal(false, false);
  if (s.holds_cine) send_pedal(true, false);
  s.holds_fluoro = s.holds_cine = false;
  spdlog::info("remote: connection {} left ({} open)", s.id(), sessions_.size());
}

void Hub::on_text(WsSession& s, const std::string& text) {
  json msg;
  try {
    msg = json::parse(text);
  } catch (const json::exception&) {
    s.reply(json{{"type", "error"}, {"code", "bad_message"}, {"message", "not JSON"}}.dump());
    return;
  }
  if (!msg.is_object() || !msg.contains("type") || !msg["type"].is_string()) {
    s.reply(json{{"type", "error"}, {"code", "bad_message"}, {"message", "a message needs a 'type'"}}.dump());
    return;
  }
  handle(s, msg);
}

void Hub::handle(WsSession& s, const json& msg) {
  const std::string type = msg["type"].get<std::string>();
  const json id = msg.contains("id") ? msg["id"] : json();
  const int64_t now_ns = realtime::monotonic_ns();
  auto error = [&](const std::string& code, const std::string& message) {
    s.reply(json{{"type", "error"}, {"id", id}, {"code", code}, {"message", message}}.dump());
  };
  const bool is_keys = type == "keys";
  if (!(is_keys ? s.keys_bucket() : s.command_bucket()).try_take(now_ns)) {
    ++rate_limited_;
    return error("rate_limited", "too many messages; slow down");
  }
  if (type == "ping") return s.reply(json{{"type", "pong"}, {"id", id}}.dump());
  if (type == "set_fps") {
    if (!msg.contains("fps") || !msg["fps"].is_number()) return error("bad_message", "'fps' must be a number");
    const double fps = msg["fps"].get<double>();
    if (!(fps >= 0.5 && fps <= limits_.max_fps))
      return error("out_of_range", "fps must lie in [0.5, " + std::to_string(limits_.max_fps) + "]");
    s.set_max_fps(fps);
    return s.reply(json{{"type", "ack"}, {"id", id}, {"fps", fps}}.dump());
  }
  if (type != "command" && type != "keyboard" && !is_keys)
    return error("bad_message", "unknown message type '" + type + "'");
  if (s.role() != Role::kController) {
    ++commands_refused_;
    return error("forbidden", "observers may watch but not control");
  }
  if (type == "keyboard") {
    if (!keyboard_) return error("unavailable", "the keyboard instrument is off (--no-keyboard-instrument)");
    if (!msg.contains("enable") || !msg["enable"].is_boolean())
      return error("bad_message", "'enable' must be true or false");
    if (!msg["enable"].get<bool>()) {
      keyboard_->disable(s.id());
      return s.reply(json{{"type", "ack"}, {"id", id}, {"keyboard", false}}.dump());
    }
    const auto wire = tracker_.wire_insertion_rotation();
    const std::string why = keyboard_->enable(s.id(), wire ? wire->first : 0.0, wire ? wire->second : 0.0);
    if (!why.empty()) {
      ++commands_refused_;
      return error("instrument_busy", why);
    }
    return s.reply(json{{"type", "ack"}, {"id", id}, {"keyboard", true}}.dump());
  }
  if (is_keys) {
    const double insert = msg.contains("insert") && msg["insert"].is_number() ? msg["insert"].get<double>() : 0.0;
    const double rotate = msg.contains("rotate") && msg["rotate"].is_number() ? msg["rotate"].get<double>() : 0.0;
    if (!keyboard_ || !keyboard_->set_keys(s.id(), insert, rotate, now_ns))
      return error("not_owner", "enable the keyboard instrument first");
    return;  // keys are frequent: no answer when all is well
  }
  const ParsedCommand parsed = parse_session_command(msg, command_limits_);
  if (const auto* err = std::get_if<CommandError>(&parsed)) {
    ++commands_refused_;
    return error(err->code, err->message);
  }
  C c = std::get<C>(parsed);
  c.utime = realtime::monotonic_us();
  sink_(c);
  ++commands_forwarded_;
  if (c.command == C::CMD_FLUORO_PEDAL) s.holds_fluoro = c.pedal_down != 0;
  if (c.command == C::CMD_CINE) s.holds_cine = c.pedal_down != 0;
  s.reply(json{{"type", "ack"}, {"id", id}, {"command", msg["command"]}}.dump());
}

void Hub::broadcast_frame(std::shared_ptr<const EncodedFrame> frame) {
  ++frames_offered_;
  last_frame_ = frame;
  for (auto& [id, weak] : sessions_)
    if (auto s = weak.lock()) s->offer_frame(frame);
}

void Hub::broadcast_state(std::shared_ptr<const std::string> state) {
  last_state_ = state;
  for (auto& [id, weak] : sessions_)
    if (auto s = weak.lock()) s->offer_state(state);
}

void Hub::broadcast_status(std::shared_ptr<const std::string> status) {
  last_status_ = status;
  for (auto& [id, weak] : sessions_)
    if (auto s = weak.lock()) s->offer_status(status);
}

void Hub::close_all() {
  auto copy = sessions_;  // closing may call leave(), which edits the map
  for (auto& [id, weak] : copy)
    if (auto s = weak.lock()) s->close();
}

void Hub::count_frame_sent(size_t) {
  ++frames_sent_;
}
void Hub::count_frame_dropped(size_t) {
  ++frames_dropped_;
}
void Hub::count_frame_pending(int64_t delta_bytes) {
  bytes_pending_ += delta_bytes;
}

HubStats Hub::stats() const {
  HubStats s;
  s.clients = clients_;
  s.connections_total = connections_total_;
  s.frames_offered = frames_offered_;
  s.frames_sent = frames_sent_;
  s.frames_dropped = frames_dropped_;
  s.bytes_pending = bytes_pending_;
  s.commands_forwarded = commands_forwarded_;
  s.commands_refused = commands_refused_;
  s.rate_limited = rate_limited_;
  return s;
}

}  // namespace pcisim::remote
